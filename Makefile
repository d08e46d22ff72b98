# glu: the two entry points of the README, and a few more.
#   make reproduce   set up .venv, then run every notebook (results/, recordings/, models/, build/figures/,
#                    build/site/; the tracked figures/ only from a full run on the real data)
#   make docs        the documentation site (build/site/index.html) again, from the last `make reproduce`
#   make test        set up .venv, then lint (ruff) and run the test suite (on every core, at most 4)
#   make lab         JupyterLab on the repository, the notebooks open as notebooks
#   make bench       speed benchmarks (glu vs pgmpy, pyAgrum, hmmlearn); make bench-reproduce: the whole run
#   make sweeps      the saved tables of the heavy grids of notebooks 10, 11 and 12 (sweeps/), again
# Variables: DATA=DIR (data folder; default: GLU_DATA_DIR, data/real, else synthetic), ARGS=... (extra flags).
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.glu-installed
DATA ?=
ARGS ?=

.PHONY: reproduce docs test lint lab bench bench-reproduce sweeps clean venv

venv: $(STAMP)

$(STAMP): pyproject.toml setup.py
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

reproduce: $(STAMP)
	$(BIN)/glu reproduce $(if $(DATA),--data $(DATA)) $(ARGS)
	$(BIN)/glu readme --if-complete

docs: $(STAMP)
	$(BIN)/python -m glu.run.site

lint: $(STAMP)
	$(BIN)/ruff check glu tests benchmarks $(wildcard notebooks/*.py)
	$(BIN)/ruff format --check glu tests benchmarks

# the suite on every core (pytest-xdist, at most 4 workers), a test file to a worker: a file's session fixtures
# (the quick run of every notebook) are made once; ARGS="-n 0" runs it in this process (pdb, -s)
test: lint
	$(BIN)/python -m pytest -n auto --maxprocesses 4 --dist loadfile $(ARGS)

# JupyterLab comes with the test extra (glu[test] includes glu[lab]): one install serves both
lab: $(STAMP)
	$(if $(DATA),GLU_DATA_DIR=$(abspath $(DATA))) $(BIN)/jupyter lab --config=jupyter_lab_config.py $(ARGS)

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_bn.py
	$(BIN)/python benchmarks/bench_hmm.py
	$(BIN)/python benchmarks/bench_training.py
	$(BIN)/python benchmarks/bench_fast_paths.py
	$(BIN)/python benchmarks/bench_kernels.py

bench-reproduce: $(STAMP)
	$(BIN)/python benchmarks/bench_reproduce.py $(if $(DATA),--data $(DATA)) $(ARGS)

# The saved tables of the heavy grids of notebooks 10, 11 and 12 (sweeps/, glu.saved): regenerate them after a
# change of what their numbers depend on. The real-data tables need DATA=DIR (the real data); the rest does not.
# Notebook 12's runs (10 seeds × 10,000 episodes, and the real person's 50 draws) take about an hour on 2 cores.
sweeps: $(STAMP)
	$(BIN)/glu correspondence -o sweeps/10_correspondence/study --workers 2
	$(BIN)/glu evaluate --config sweeps/11_corpus_evaluation/sweep.toml --data synthetic --workers 2 \
		-o build/sweeps/11-synthetic --save sweeps/11_corpus_evaluation/synthetic
	$(if $(DATA),$(BIN)/glu evaluate --config sweeps/11_corpus_evaluation/sweep.toml --data $(DATA) --workers 2 \
		-o build/sweeps/11-real --save sweeps/11_corpus_evaluation/real,@echo "make sweeps: give DATA=DIR for notebook 11's real-data tables")
	$(BIN)/glu learning-curves --data synthetic --workers 2 -o sweeps/12_learning_from_effects/synthetic
	$(if $(DATA),$(BIN)/glu learning-curves --part all --data $(DATA) --workers 2 \
		-o sweeps/12_learning_from_effects/real,@echo "make sweeps: give DATA=DIR for notebook 12's real-data runs")

clean:
	rm -rf $(VENV) build *.egg-info
