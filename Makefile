# glu: the two entry points of the README.
#   make reproduce   set up .venv, then run every notebook (figures/, recordings/, results summary)
#   make test        set up .venv, then lint (ruff) and run the test suite
# Variables: DATA=DIR (data folder; default: GLU_DATA_DIR, data/real, else synthetic), ARGS=... (extra flags).
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.glu-installed
DATA ?=
ARGS ?=

.PHONY: reproduce test lint bench clean venv

venv: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

reproduce: $(STAMP)
	$(BIN)/glu reproduce $(if $(DATA),--data $(DATA)) $(ARGS)

lint: $(STAMP)
	$(BIN)/ruff check glu tests benchmarks $(wildcard notebooks/*.py)
	$(BIN)/ruff format --check glu tests benchmarks

test: lint
	$(BIN)/python -m pytest $(ARGS)

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_bn.py

clean:
	rm -rf $(VENV) build *.egg-info
