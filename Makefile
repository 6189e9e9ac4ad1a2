# oceanloc developer commands. `make demo` and `make test` work on a fresh machine: each creates
# .venv if it is missing and installs the package with what it needs (pyproject.toml) first.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp

.PHONY: demo test test-slow test-loaded bench lint install system gnatss setup clean

# GNATSS (the community's GNSS-A package) is the oracle of the GNSS-A tests and benchmark. Its pins
# (xarray<2025, pydantic==2.8.2, numba) clash with ours, so it gets its own environment, built once
# (stamp file) where pip reaches PyPI; without it those tests skip with a message naming gnatss.
GNATSS_VERSION := 0.4.2
GNATSS_VENV := .venv-gnatss
GNATSS_STAMP := $(GNATSS_VENV)/.installed-$(GNATSS_VERSION)

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

install: $(STAMP)

$(GNATSS_STAMP):
	@($(PYTHON) -m venv $(GNATSS_VENV) \
	  && $(GNATSS_VENV)/bin/python -m pip install --quiet 'gnatss==$(GNATSS_VERSION)' \
	  && touch $(GNATSS_STAMP)) \
	  || echo "gnatss $(GNATSS_VERSION) could not be installed (no PyPI?): its oracle tests will skip"

gnatss: $(GNATSS_STAMP)

# System components that some tests run for real (gpsd, socat, chromium): installed where possible, else
# those tests skip with a message naming the component.
system:
	@bash scripts/system-deps.sh

demo: $(STAMP)
	$(BIN)/oceanloc demo --out oceanloc-demo

# The set-up steps run side by side (pip, apt-get and GNATSS's pip are mostly waiting on downloads);
# tests run in as many processes as there are cores (pytest-xdist), a test file per process at a time.
setup:
	@$(MAKE) --no-print-directory -j3 install system gnatss

test: setup
	$(BIN)/python -m pytest -m "not slow" -n auto --dist loadfile

# The suite under background load (BUSY spinning processes, ROUNDS runs in a row): it must pass every time.
test-loaded: setup
	BUSY=$(or $(BUSY),4) ROUNDS=$(or $(ROUNDS),3) bash scripts/test-under-load.sh

test-slow: setup
	$(BIN)/python -m pytest -m slow

bench: $(STAMP) gnatss
	$(BIN)/python benchmarks/run.py $(BENCH)

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks examples
	$(BIN)/ruff format --check src tests benchmarks examples

clean:
	rm -rf $(VENV) $(GNATSS_VENV) build *.egg-info src/*.egg-info .pytest_cache .ruff_cache
