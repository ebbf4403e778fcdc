# Two commands on a fresh machine with python3 and make:
#   make reproduce   every notebook at full fidelity -> build/notebooks, build/figures, build/report.md
#   make test        unit tests + every notebook in quick mode
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

.PHONY: all test unit notebooks-quick reproduce bench clean distclean venv

all: test

venv: $(STAMP)

# (Re)install only when pyproject.toml changed.
$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[notebooks,test]'
	$(PY) -m ipykernel install --sys-prefix --name python3 --display-name "Python 3 (cislunar)" >/dev/null
	touch $(STAMP)

test: $(STAMP)
	$(PY) -m pytest -n 2 --dist loadgroup tests

unit: $(STAMP)
	$(PY) -m pytest -n 2 -m "not notebook" tests

notebooks-quick: $(STAMP)
	$(PY) -m cislunar.notebooks --quick

reproduce: $(STAMP)
	$(PY) -m cislunar.notebooks

bench: $(STAMP)
	$(PY) -m benchmarks

clean:
	rm -rf build .pytest_cache .hypothesis

distclean: clean
	rm -rf $(VENV) *.egg-info
