# Two commands on a fresh machine with python3 (3.11) and make:
#   make reproduce   every notebook at full fidelity -> build/notebooks, build/figures, build/report.md,
#                    then the static HTML book build/book/index.html (checked by tests/publish/test_book.py).
#                    The run is staged and replaces build/ only when every notebook succeeded; Ctrl-C ends it.
#   make test        unit tests + every notebook in quick mode + a book built from them, all in a temporary
#                    directory; it fails if it left anything in the repository outside .venv/ (its scratch)
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
EXTRAS := notebooks,book,cluster,test
# One BLAS thread per process: the tests run in two pytest-xdist workers on a two-core machine.
export OMP_NUM_THREADS ?= 1
export OPENBLAS_NUM_THREADS ?= 1
export MKL_NUM_THREADS ?= 1
export PYTHONHASHSEED := 0
export JUPYTER_PREFER_ENV_PATH := 1

.PHONY: all test unit notebooks-quick reproduce notebooks notebook book check-book bench clean distclean venv
# pytest's cache (the quick notebooks' last run times) lives in the venv, the one scratch folder of `make test`
PYTEST := $(PY) -m pytest -o cache_dir=$(VENV)/pytest-cache
# What `make test` may leave behind: nothing but .venv/ (compared before and after)
REPO_STATE = git status --porcelain --ignored 2>/dev/null | grep -v '^!! \.venv/$$' || true

all: test

venv: $(STAMP)

# (Re)install only when pyproject.toml changed.
$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[$(EXTRAS)]'
	$(PY) -m ipykernel install --sys-prefix --name python3 --display-name "Python 3 (cislunar)" >/dev/null
	touch $(STAMP)

test: $(STAMP)
	@$(REPO_STATE) > $(VENV)/repo-state-before
	@$(PYTEST) -n 2 --dist loadgroup tests; status=$$?; \
	$(REPO_STATE) > $(VENV)/repo-state-after; \
	if ! cmp -s $(VENV)/repo-state-before $(VENV)/repo-state-after; then \
	    echo "make test changed the repository outside .venv/:"; diff $(VENV)/repo-state-before $(VENV)/repo-state-after; \
	    exit 1; fi; exit $$status

unit: $(STAMP)
	$(PYTEST) -n 2 -m "not notebook" tests

# Quick mode into build-quick/ (never build/).
notebooks-quick: $(STAMP)
	$(PY) -m cislunar.publish.notebooks --quick

reproduce: notebooks book check-book

notebooks: $(STAMP)
	$(PY) -m cislunar.publish.notebooks

# One notebook (or several), full fidelity into build/ unless ARGS says --quick:
#   make notebook NB=05 ARGS="-p N_NODES=24"      make notebook NB="01 04" ARGS=--quick
notebook: $(STAMP)
	$(PY) -m cislunar.publish.notebooks $(NB) $(ARGS)

# Rebuild build/book from the executed notebooks in build/notebooks, without executing anything.
book: $(STAMP)
	$(PY) -m cislunar.publish.book

# The book checks (pages, links, offline, no error output, math typeset in headless Chromium) on build/book.
check-book: $(STAMP)
	CISLUNAR_BOOK_BUILD=build $(PY) -m pytest -q -p no:cacheprovider tests/publish/test_book.py

bench: $(STAMP)
	$(PY) -m benchmarks

clean:
	rm -rf build build-quick build-scratch build-incomplete build-quick-incomplete build.staging-* \
	    build-quick.staging-* .build*.old-* .pytest_cache .hypothesis

distclean: clean
	rm -rf $(VENV) *.egg-info
