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
# One BLAS thread per process: the tests run in two pytest-xdist workers on a two-core machine.
export OMP_NUM_THREADS ?= 1
export OPENBLAS_NUM_THREADS ?= 1
export MKL_NUM_THREADS ?= 1
export PYTHONHASHSEED := 0
export JUPYTER_PREFER_ENV_PATH := 1
# Byte code in .venv/pycache, never beside the sources (measured gain and reasons above the test target)
export PYTHONPYCACHEPREFIX := $(CURDIR)/$(VENV)/pycache
export PYTHONDONTWRITEBYTECODE :=
# hypothesis keeps its example database and caches in the venv, not in the repository
export HYPOTHESIS_STORAGE_DIRECTORY ?= $(CURDIR)/.venv/hypothesis

.PHONY: all test unit lint notebooks-quick reproduce notebooks notebook book check-book bench clean distclean venv lock
# pytest's cache (the quick notebooks' last run times) lives in the venv, the one scratch folder of `make test`
PYTEST := $(PY) -m pytest -o cache_dir=$(VENV)/pytest-cache
# What `make test` may leave behind: nothing but .venv/ (compared before and after)
REPO_STATE = { git status --porcelain --ignored 2>/dev/null | grep -v '^!! \.venv/$$' || true; }

all: test

venv: $(STAMP)

# The bootstrap installs the exact versions of requirements.lock (hashes checked) with uv, then the package itself
# (editable, no dependencies).  uv is pinned in the lock too; pip only installs uv.  Measured on this 2-core
# machine under load: 31-34 s with uv against 136 s with pip (environment.md).  `make lock` refreshes the lock
# from pyproject.toml; INSTALLER=pip installs the same lock with pip.
INSTALLER ?= uv
$(STAMP): pyproject.toml requirements.lock
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
ifeq ($(INSTALLER),uv)
	$(PY) -m pip install --quiet --disable-pip-version-check "$$(grep -o '^uv==[^ ]*' requirements.lock)"
	$(VENV)/bin/uv pip install --quiet --python $(PY) --require-hashes -r requirements.lock
	$(VENV)/bin/uv pip install --quiet --python $(PY) --no-deps -e .
else
	$(PY) -m pip install --quiet --disable-pip-version-check --require-hashes -r requirements.lock
	$(PY) -m pip install --quiet --disable-pip-version-check --no-deps -e .
endif
	$(PY) -m ipykernel install --sys-prefix --name python3 --display-name "Python 3 (cislunar)" >/dev/null
	# The kernel logs only errors: a notebook run by hand with papermill (TCP transport) would otherwise print
	# ipykernel's unencrypted-TCP warning on every start (the runner uses IPC and never sees it).
	$(PY) -c "import json, pathlib, sys; p = pathlib.Path(sys.prefix, 'share/jupyter/kernels/python3/kernel.json'); k = json.loads(p.read_text()); a = '--IPKernelApp.log_level=ERROR'; k['argv'] += [] if a in k['argv'] else [a]; p.write_text(json.dumps(k, indent=1))"
	touch $(STAMP)

# Re-resolve every dependency (newest versions within pyproject.toml's ranges) into requirements.lock.
lock: $(STAMP)
	$(VENV)/bin/uv pip compile pyproject.toml --extra notebooks --extra book --extra cluster --extra test \
	    --python-version 3.11 --python-platform linux --generate-hashes --no-header -q -o requirements.lock

# (the two exports are at the top of this file and serve every target: `make reproduce` starts a kernel per notebook)
# Byte code of every module (standard library, site-packages, cislunar, pytest's rewritten test modules) is kept in
# .venv/pycache, the scratch folder, never beside the sources (where it would also fail the repository check below).
# `make test` starts dozens of Python processes (two workers, a kernel per notebook and per runner test, spawned
# pools); without written byte code (PYTHONDONTWRITEBYTECODE=1 here, and uv installs none) each one compiled numpy,
# scipy, matplotlib, cvxpy and cislunar again.  Measured 2026-11-26 (2 cores, load 5-9) on a uv-installed venv:
# importing that stack 4.3 s CPU per process against 1.8 s with this cache warm; the runner and notebook unit tests
# (10 tests, ~11 processes) 42-44 s against 22 s CPU; collecting the suite 10.6 against 6.0 s per worker.
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
