# oceanloc developer commands. `make demo` and `make test` work on a fresh machine: each creates
# .venv if it is missing and installs the package with what it needs (pyproject.toml) first.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp

.PHONY: demo test test-slow bench lint install system clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

install: $(STAMP)

# System components that some tests run for real (gpsd, socat, chromium): installed where possible, else
# those tests skip with a message naming the component.
system:
	@bash scripts/system-deps.sh

demo: $(STAMP)
	$(BIN)/oceanloc demo --out oceanloc-demo

# Tests run in as many processes as there are cores (pytest-xdist), a test file per process at a time.
test: $(STAMP) system
	$(BIN)/python -m pytest -m "not slow" -n auto --dist loadfile

test-slow: $(STAMP) system
	$(BIN)/python -m pytest -m slow

bench: $(STAMP)
	$(BIN)/python benchmarks/run.py $(BENCH)

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks examples
	$(BIN)/ruff format --check src tests benchmarks examples

clean:
	rm -rf $(VENV) build *.egg-info src/*.egg-info .pytest_cache .ruff_cache
