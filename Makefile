# Sensor-fusion teaching labs. `make help` lists the targets.
include grading/student/course.mk
LABS    ?= $(sort $(notdir $(wildcard solutions/[0-9][0-9]_*)))
NBVAL   := --nbval --nbval-current-env --nbval-sanitize-with tests/nbval_sanitize.cfg

# Widget state (a snapshot of every slider and figure) bloats the notebook and is rebuilt live in JupyterLab.
define STRIP_WIDGET_STATE
import sys, nbformat
nb = nbformat.read(sys.argv[1], as_version=4)
nb.metadata.pop("widgets", None)
nbformat.write(nb, sys.argv[1])
endef
export STRIP_WIDGET_STATE

.PHONY: formgrader lint format test test-all test-budget solutions labs data release clean

formgrader: env  ## instructors: JupyterLab on the course root with nbgrader's Formgrader and Create Assignment [ARGS=...]
	@echo "==> JupyterLab for instructors (Nbgrader menu -> Formgrader) -- open the URL printed below; Ctrl-C to stop"
	@$(BIN)/jupyter lab --no-browser --notebook-dir=. $(SETTINGS) $(ALLOW_ROOT) $(ARGS)

lint: env  ## ruff on the Python sources: its lint rules and its format (pyproject.toml; the notebooks are not linted)
	@echo "==> ruff check: pyflakes, pycodestyle and bugbear on lib/, tests/, grading/, hub/"
	@$(BIN)/ruff check .
	@echo "==> ruff format --check: the sources as the formatter writes them (make format applies it)"
	@$(BIN)/ruff format --check .

format: env  ## authors: write the Python sources in the formatter's layout (what make lint checks)
	@$(BIN)/ruff format .

# One pytest run holds the unit tests, the library's doctests and strict nbval on every solution, on both cores
# (-n 2; each test file stays in one process, so a module's fixture -- a class graded once -- serves all its tests;
# the files of the longest fixtures start first: tests/conftest.py).
PYTEST  := $(BIN)/python -m pytest tests lib/fusionlab solutions --doctest-modules $(NBVAL) -q --durations=10 \
           -n 2 --dist loadfile --no-loadscope-reorder

test: env  ## the fast tests (a few minutes): every module, every solution under strict nbval, one graded class
	@echo "==> unit tests, doctests, strict nbval on every solution, one class graded by the judge (slow tier: make test-all)"
	@$(PYTEST) -m "not slow"

test-all: env  ## every test (CI): the fast tests, plus every lab graded in the sandbox, the browser, long records
	@echo "==> the whole suite: make test's tests and the slow tier (pytest -m slow)"
	@$(PYTEST)

test-budget: env  ## time make test's tests (median of 3) and each lab's Run All against their budgets
	@$(BIN)/python tests/budget.py both --repeat 3

solutions: env  ## re-execute every solution notebook in place (authors; one lab: make solutions LABS=01_euler_rotations)
	@for lab in $(LABS); do echo "==> executing solutions/$$lab/$$lab.ipynb"; \
	  $(BIN)/jupyter nbconvert --to notebook --execute --inplace --ExecutePreprocessor.timeout=120 \
	    solutions/$$lab/$$lab.ipynb 2>&1 | grep -v "without encryption" ; test $${PIPESTATUS[0]} = 0 || exit 1; \
	  $(BIN)/python -c "$$STRIP_WIDGET_STATE" solutions/$$lab/$$lab.ipynb || exit 1; done

labs: env  ## regenerate the student notebooks in labs/ from solutions/, and labs/docs (what the labs link to)
	@$(BIN)/python -m grading.stamp $(LABS)
	@db=$$(mktemp -d)/gradebook.db; for lab in $(LABS); do echo "==> generating labs/$$lab"; \
	  $(BIN)/nbgrader generate_assignment $$lab --force --log-level=ERROR --db=sqlite:///$$db || exit 1; done
	@echo "==> copying the documents the labs link to into labs/docs"
	@$(BIN)/python -m grading.release --labs-docs >/dev/null

data: env  ## regenerate the datasets in data/ (byte-identical; checksums in data/README.md)
	@echo "==> regenerating data/lab03 (terminal logs, true angles) and the Lab 03 spreadsheet"
	@$(BIN)/python -m fusionlab.simulate --out data/
	@$(BIN)/python -m fusionlab.spreadsheet --log data/lab03/motion.log --xlsx data/lab03_fusion.xlsx
	@echo "==> regenerating data/phone (BROAD trial 2 written in phone apps' export formats)"
	@$(BIN)/python -m fusionlab.recordings --out data/phone/ >/dev/null

# Grading: the course's own gradebook.db (the instructor's, git-ignored), student code run only in the sandbox.
WORKERS ?= 2
.PHONY: gradebook grade

gradebook: env  ## record the labs (or LABS=...) in the course's gradebook.db for grading; labs/ is left as it is
	@rel=$$(mktemp -d); for lab in $(LABS); do echo "==> recording $$lab in gradebook.db"; \
	  $(BIN)/nbgrader generate_assignment $$lab --force --log-level=ERROR \
	    --CourseDirectory.release_directory=$$rel || { rm -rf $$rel; exit 1; }; done; rm -rf $$rel

grade: env  ## sandboxed autograde of a class: make grade LAB=02_kalman_falling_body [WORKERS=2] [STUDENT=id]
	@test -n "$(LAB)" || { echo "usage: make grade LAB=NN_name [WORKERS=2] [STUDENT=id]"; exit 2; }
	@$(BIN)/python -m grading.classgrade $(LAB) --workers $(WORKERS) $(if $(STUDENT),--student $(STUDENT))

# The capstone (Lab 13): scored on the BROAD trials the course does not ship, in the sandbox (grading/capstone/).
CLASS ?= class
.PHONY: capstone-data capstone capstone-bar

capstone-data: env  ## instructors: fetch the capstone's 31 hidden BROAD trials once (checked download into the cache)
	@$(BIN)/python -m grading.capstone fetch

capstone: env  ## the capstone's leaderboard: make capstone CLASS=name (needs make capstone-data first)
	@$(BIN)/python -m grading.capstone grade --class $(CLASS) --workers $(WORKERS)

capstone-bar: env  ## authors: re-make the bar Lab 13 reads (every filter on the shipped trials; about 2 minutes)
	@$(BIN)/python -m fusionlab.capstone

# The course on a JupyterHub on this machine (hub/, docs/hub.md): as root, Ctrl-C stops it all.
HUB_STUDENTS ?= 3
HUB_PORT     ?= 8000
HUB_DIR      ?= /srv/fusionlab-hub
.PHONY: hub hub-env hub-remove

$(VENV)/.hub-installed: $(VENV)/.installed hub/requirements.txt
	@echo "==> installing JupyterHub and the idle culler into $(VENV) (hub/requirements.txt)"
	@$(BIN)/python -m pip install --quiet -r hub/requirements.txt
	@touch $@

hub/node_modules/.package-lock.json: hub/package.json hub/package-lock.json
	@echo "==> installing the proxy (configurable-http-proxy, pinned in hub/package-lock.json) into hub/node_modules"
	@command -v npm >/dev/null || { echo "make hub needs Node.js and npm (Debian: apt-get install nodejs npm)"; exit 2; }
	@cd hub && npm ci --no-audit --no-fund --loglevel=error
	@touch $@

hub-env: $(VENV)/.hub-installed hub/node_modules/.package-lock.json  ## install what make hub needs (JupyterHub, the proxy)

hub: hub-env  ## as root: JupyterHub on 127.0.0.1:8000, an instructor and HUB_STUDENTS=3 student accounts; Ctrl-C stops it
	@$(BIN)/python -m hub.run --students $(HUB_STUDENTS) --port $(HUB_PORT) --dir $(HUB_DIR) $(ARGS)

hub-remove:  ## remove the hub's accounts and its folder (HUB_DIR)
	@$(BIN)/python -m hub.run --remove --dir $(HUB_DIR)

release: env  ## the student course: release/course/ and release/fusionlab-course.tar.gz (no solutions, no grading)
	@$(BIN)/python -m grading.release --out release

clean:  ## remove grading scratch folders and the release (keeps .venv)
	rm -rf submitted autograded feedback gradebook.db .pytest_cache release
