# What the course repository's Makefile and the student release's Makefile share: the environment in .venv and
# JupyterLab on labs/ as a student sees it, Validate in a terminal and the benchmark. Both include this file (the release ships it beside its Makefile), so
# a student runs the very recipes the course is tested with.
SHELL   := /bin/bash
PYTHON  ?= $(shell command -v python3.11 || command -v python3)
VENV    ?= .venv
BIN     := $(abspath $(VENV))/bin
# Jupyter, the kernels it starts and nbgrader (which shells out to `alembic` by name) must find this environment's
# programs first.
export PATH := $(BIN):$(PATH)
export MPLBACKEND := Agg
# The student's view (jupyter/README.md): nbgrader's instructor tools and the news pop-up off, when the folder is there.
STUDENT_VIEW := $(if $(wildcard jupyter),JUPYTER_CONFIG_PATH=$(CURDIR)/jupyter$(if $(JUPYTER_CONFIG_PATH),:$(JUPYTER_CONFIG_PATH)))
SETTINGS     := $(if $(wildcard jupyter/lab/settings),--LabApp.app_settings_dir=$(CURDIR)/jupyter/lab/settings)
ALLOW_ROOT   := $(if $(filter 0,$(shell id -u)),--allow-root)
ARGS    ?=

.PHONY: help env lab validate bench

help:  ## list the targets
	@grep -hE '^[a-z-]+:.*## ' $(filter %.mk,$(MAKEFILE_LIST)) $(filter-out %.mk,$(MAKEFILE_LIST)) | sed 's/:.*## /\t/' | column -t -s $$'\t'

$(VENV)/.installed: environment.txt pyproject.toml
	@echo "==> setting up $(VENV) from environment.txt (first time: a few minutes)"
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	@$(BIN)/python -m pip install --quiet --upgrade pip
	@$(BIN)/python -m pip install --quiet -r environment.txt
	@touch $@

env: $(VENV)/.installed  ## create .venv and install environment.txt

lab: env  ## start JupyterLab on labs/ as a student sees it (prints the URL to open; Ctrl-C stops it)
	@echo "==> JupyterLab on labs/ -- open the URL printed below; Ctrl-C to stop"
	@$(STUDENT_VIEW) $(BIN)/jupyter lab --no-browser --notebook-dir=labs $(SETTINGS) $(ALLOW_ROOT) $(ARGS)

validate: env  ## what the Validate button reports, in the terminal: make validate LAB=01_euler_rotations
	@test -n "$(LAB)" || { echo "usage: make validate LAB=NN_name"; exit 2; }
	@$(STUDENT_VIEW) $(BIN)/nbgrader validate labs/$(LAB)/$(LAB).ipynb

bench: env  ## every filter on every available BROAD trial: table, CSV and figure in .bench/
	@echo "==> benchmark (the trials shipped in data/broad/, plus any in FUSIONLAB_BROAD_DIR or the cache)"
	@$(BIN)/python -m fusionlab.bench --out .bench
