# Two commands on a fresh machine with python3 (3.11) and make:
#   make reproduce   every notebook at full fidelity -> build/notebooks, build/figures, build/report.md,
#                    then the static HTML book build/book/index.html (checked by tests/publish/test_book.py)
#   make test        unit tests + every notebook in quick mode + a book built from them, all in a temporary
#                    directory (build/ only ever holds a full run)
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

.PHONY: all test unit notebooks-quick reproduce notebooks book check-book bench clean distclean venv

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
	$(PY) -m pytest -n 2 --dist loadgroup tests

unit: $(STAMP)
	$(PY) -m pytest -n 2 -m "not notebook" tests

# Quick mode into build-quick/ (never build/).
notebooks-quick: $(STAMP)
	$(PY) -m cislunar.publish.notebooks --quick

reproduce: notebooks book check-book

notebooks: $(STAMP)
	$(PY) -m cislunar.publish.notebooks

# Rebuild build/book from the executed notebooks in build/notebooks, without executing anything.
book: $(STAMP)
	$(PY) -m cislunar.publish.book

# The book checks (pages, links, offline, no error output, math typeset in headless Chromium) on build/book.
check-book: $(STAMP)
	CISLUNAR_BOOK_BUILD=build $(PY) -m pytest -q -p no:cacheprovider tests/publish/test_book.py

bench: $(STAMP)
	$(PY) -m benchmarks

clean:
	rm -rf build build-quick .pytest_cache .hypothesis

distclean: clean
	rm -rf $(VENV) *.egg-info
