# Sensor-fusion teaching labs. `make help` lists the targets.
SHELL   := /bin/bash
PYTHON  ?= $(shell command -v python3.11 || command -v python3)
VENV    := .venv
BIN     := $(abspath $(VENV))/bin
# nbgrader shells out to `alembic` by name: the environment's bin must be on PATH for every call.
export PATH := $(BIN):$(PATH)
export MPLBACKEND := Agg
LABS    := $(sort $(notdir $(wildcard solutions/[0-9][0-9]_*)))
NBVAL   := --nbval --nbval-current-env --nbval-sanitize-with tests/nbval_sanitize.cfg

.PHONY: help lab test solutions labs env clean

help:  ## list the targets
	@grep -E '^[a-z]+:.*## ' $(MAKEFILE_LIST) | sed 's/:.*## /\t/' | column -t -s $$'\t'

$(VENV)/.installed: environment.txt pyproject.toml
	@echo "==> setting up $(VENV) from environment.txt (first time: a few minutes)"
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	@$(BIN)/python -m pip install --quiet --upgrade pip
	@$(BIN)/python -m pip install --quiet -r environment.txt
	@touch $@

env: $(VENV)/.installed  ## create .venv and install environment.txt

lab: env  ## start JupyterLab on labs/ (prints the URL; no browser needed)
	@echo "==> JupyterLab on labs/ -- open the URL printed below; Ctrl-C to stop"
	@$(BIN)/jupyter lab --no-browser --notebook-dir=labs

test: env  ## the whole test suite: unit tests, lab sync, strict nbval on every solution, autograde
	@echo "==> unit and pipeline tests"
	@$(BIN)/python -m pytest tests -q
	@echo "==> strict nbval on every solution notebook"
	@$(BIN)/python -m pytest -q $(NBVAL) solutions

solutions: env  ## re-execute every solution notebook in place (authors)
	@for lab in $(LABS); do echo "==> executing solutions/$$lab/$$lab.ipynb"; \
	  $(BIN)/jupyter nbconvert --to notebook --execute --inplace \
	    --ExecutePreprocessor.timeout=120 solutions/$$lab/$$lab.ipynb || exit 1; done

labs: env  ## regenerate the student notebooks in labs/ from solutions/
	@for lab in $(LABS); do echo "==> generating labs/$$lab"; \
	  $(BIN)/nbgrader generate_assignment $$lab --force --log-level=WARN || exit 1; done
	@rm -f gradebook.db

clean:  ## remove grading scratch folders (keeps .venv)
	rm -rf submitted autograded feedback gradebook.db .pytest_cache
