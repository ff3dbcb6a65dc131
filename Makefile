# Two entry points (see README), and the manual (`make docs`): `make report` (the batch report on the bundled data) and
# `make test`. Both create or refresh the local virtual environment .venv first.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp
export PATH := $(abspath $(BIN)):$(PATH)
export MPLBACKEND ?= Agg

.PHONY: report test test-all test-fast test-slow test-browser browser-deps peers-deps lint format evaluate bench calibrate bytecode clean-venv student grade grading-rates book slides docs

$(STAMP): pyproject.toml lorisnb/_version.py lorisnb/core/trajectory/_rotations.c
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip
	$(BIN)/python -m pip install -e '.[all,dev]'
	touch $(STAMP)

# lorisnb's bytecode, written once (incremental): with PYTHONDONTWRITEBYTECODE set (many CI machines),
# an editable install would otherwise compile every module it imports at each start
bytecode: $(STAMP)
	$(BIN)/python -m compileall -q lorisnb

report: bytecode
	$(BIN)/lorisnb report

evaluate: bytecode
	$(BIN)/lorisnb evaluate --scale auto --csv results/evaluate.csv $(or $(DATA),../shared/data)/openloris-scene/icra20_results

# the tests on every core (pytest-xdist). PYTEST_WORKERS=1 runs them in one process.
PYTEST_WORKERS ?= auto
PYTEST_ONCE = $(BIN)/python -m pytest -q
PYTEST = $(PYTEST_ONCE) -n $(PYTEST_WORKERS) --dist loadgroup

# the newcomer's command (README): the fast tests but the thorough ones (each several seconds: peers run
# side by side, many draws, whole processes) and one run of each notebook, a few minutes; the notebook
# runs one at a time (as test-all's, below), their kernels forked warm as a report's (tests/notebooks)
test: bytecode
	$(PYTEST) -m "not slow and not browser and not thorough"
	$(PYTEST_ONCE) -m "smoke and not browser"

# everything but the browser: the fast tests on every core, then the slow ones (notebooks, reports, the
# installed wheel) one at a time: papermill kernels run side by side under pytest-xdist stalled now and
# then with an idle kernel. On 2026-11-28 one kernel at a time on one xdist worker, beside the other
# worker's tests, stalled twice in two runs, each time in a cell displaying an ipywidgets explorer
# (threshold_sensitivity's ThresholdExplorer; an earlier stall: metrics_primer's FaultExplorer): the
# kernel idle after the cell (py-spy), nbclient waiting for its execute_reply on the shell channel
# (jupyter/nbclient#312, open: "when cell contains ipywidget, execute cell will sometimes block"); CI
test-all: bytecode peers-deps
	$(PYTEST) -m "not slow and not browser"
	$(PYTEST_ONCE) -m "slow and not browser"

test-fast: bytecode
	$(PYTEST) -m "not slow and not browser"

test-slow: bytecode peers-deps
	$(PYTEST) -m "slow and not browser"

# Debian's Chromium and its driver (apt, as root or with sudo), where missing
browser-deps:
	@command -v chromium >/dev/null && command -v chromedriver >/dev/null || { \
	  SUDO=$$(test "$$(id -u)" = 0 || echo sudo); \
	  $$SUDO apt-get update -qq && $$SUDO apt-get install -y -qq chromium chromium-driver; }

# what the slow tests build the C++ peers with (tests/peers.py: the KITTI devkit with g++; OpenVINS'
# ov_eval with g++, Eigen and Boost.Filesystem's headers and library), from Debian's packages (apt, as
# root or with sudo), where missing. Where the peers folder holds neither C++ peer, nothing is built:
# nothing to install.
PEERS_DIR ?= $(or $(LORISNB_PEERS),$(HOME)/.cache/lorisnb/peers)
peers-deps:
	@test -d "$(PEERS_DIR)/open_vins" || test -d "$(PEERS_DIR)/kitti_devkit" || { \
	  echo "peers-deps: no C++ peer in $(PEERS_DIR) (tests/peers.py): nothing to install"; exit 0; }; \
	command -v g++ >/dev/null \
	  && { test -f /usr/include/eigen3/Eigen/Core || test -f /usr/local/include/eigen3/Eigen/Core; } \
	  && test -f /usr/include/boost/filesystem.hpp && ls /usr/lib/*/libboost_filesystem.so >/dev/null 2>&1 || { \
	  SUDO=$$(test "$$(id -u)" = 0 || echo sudo); \
	  $$SUDO apt-get update -qq && $$SUDO apt-get install -y -qq g++ libeigen3-dev libboost-filesystem-dev; }

# the notebooks in JupyterLab in headless Chromium (screenshots in results/browser/), a report and the
# manual offline (built first where build/docs/ has none)
test-browser: $(STAMP) browser-deps
	test -f "$(DOCS_OUT)/index.html" || $(MAKE) docs
	$(BIN)/python -m pytest -q -m browser

lint: $(STAMP)
	$(BIN)/ruff check lorisnb tests benchmarks notebooks docs/*.py
	$(BIN)/ruff format --check lorisnb tests benchmarks notebooks docs/*.py
	$(BIN)/mypy
	$(BIN)/lint-imports

format: $(STAMP)
	$(BIN)/ruff format lorisnb tests benchmarks notebooks docs/*.py
	$(BIN)/ruff check --fix lorisnb tests benchmarks notebooks docs/*.py

bench: bytecode
	$(BIN)/python -m pip install -q 'polars>=1'  # a reading baseline (issue 47), for the bench only
	$(BIN)/python benchmarks/bench.py

# the regression gate's measured error rates: false alarms and power by trial count (docs/guide/regression-gating.md)
calibrate: bytecode
	$(BIN)/python benchmarks/calibrate.py

clean-venv:
	rm -rf $(VENV)

# --- teaching (teaching/README.md): the tools live in .venv-teach/, layered on .venv, because
# Jupyter Book 1 needs markdown-it-py < 4; nbgrader runs from teaching/ (its nbgrader_config.py)
TEACH := .venv-teach
TEACH_STAMP := $(TEACH)/.installed-stamp
# (absolute paths: the nbgrader commands run after `cd "$(COURSE)"`)
TEACH_ENV = PATH="$(abspath $(TEACH))/bin:$(abspath $(BIN)):$$PATH" \
	JUPYTER_PATH="$$("$(abspath $(BIN))/python" -c 'import nbconvert, pathlib; print(pathlib.Path(nbconvert.__file__).parents[4] / "share" / "jupyter")')"
LAB := lab1_lifelong_metrics

$(TEACH_STAMP): $(STAMP) teaching/requirements.txt
	test -x $(TEACH)/bin/python || $(PYTHON) -m venv $(TEACH)
	$(BIN)/python -c "import sysconfig; print('import site; site.addsitedir(%r)' % sysconfig.get_paths()['purelib'])" \
	  > "$$($(TEACH)/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')/lorisnb-venv.pth"
	$(TEACH)/bin/python -m pip install -r teaching/requirements.txt
	$(TEACH)/bin/python -m pip install --no-deps django-static-mathjax==3.2.2.1 sphinx-revealjs==3.2.1
	touch $@

# where the teaching targets write (default: the checkout, as before). COURSE: nbgrader's course
# folder (release/, submitted/, autograded/, feedback/, gradebook.db, grades.csv); the labs' sources
# stay in teaching/source. BOOK_OUT and SLIDES_OUT are replaced only when the kit built them.
COURSE ?= teaching
BOOK_OUT ?= build/book
SLIDES_OUT ?= build/slides
NBGRADER = cd "$(COURSE)" && $(TEACH_ENV) JUPYTER_CONFIG_PATH="$(abspath teaching)" nbgrader
NBGRADER_ARGS = --CourseDirectory.source_directory="$(abspath teaching/source)"

# the student version of every lab (no solutions, no hidden tests) into $(COURSE)/release/
student: $(TEACH_STAMP)
	mkdir -p "$(COURSE)"
	$(NBGRADER) generate_assignment $(LAB) --force $(NBGRADER_ARGS)

# grade $(COURSE)/submitted/ in the sandbox (demo students written when it holds none): grades.csv,
# exports/ (Canvas, Moodle, Gradescope), graded/<student>/<lab>/ (teaching/README.md, "Grading");
# GRADE_ARGS: more options of teaching/grade.py (--roster, --due, --late-per-day, --timeout, ...)
grade: student
	cd "$(COURSE)" && ls -d submitted/*/ >/dev/null 2>&1 || $(TEACH_ENV) python "$(abspath teaching/demo_submissions.py)" .
	$(TEACH_ENV) python teaching/grade.py "$(COURSE)" --source teaching/source --lab $(LAB) $(GRADE_ARGS)

# the offline book of the primer and the labs (Jupyter Book 1 + sphinx-exercise) into $(BOOK_OUT)/
grading-rates: $(TEACH_STAMP)  # how often lab 1's grade is wrong (docs/guide/teaching.md); RATES_ARGS=--quick: a minute
	$(TEACH_ENV) python teaching/grading_error_rates.py $(RATES_ARGS)

book: $(TEACH_STAMP)
	$(TEACH_ENV) python teaching/book.py "$(BOOK_OUT)"

# reveal.js slides of the primer and the labs (executed), reveal.js and MathJax beside them: $(SLIDES_OUT)/
slides: $(TEACH_STAMP)
	$(TEACH_ENV) python teaching/slides.py "$(SLIDES_OUT)"

# --- the manual (docs/build.py): Sphinx + MyST + myst-nb in .venv-docs/, layered on .venv (myst-parser 3
# needs markdown-it-py < 4, as the teaching book does); MathJax served from the manual itself
DOCS := .venv-docs
DOCS_STAMP := $(DOCS)/.installed-stamp
DOCS_OUT ?= build/docs

$(DOCS_STAMP): $(STAMP) docs/requirements.txt
	test -x $(DOCS)/bin/python || $(PYTHON) -m venv $(DOCS)
	$(BIN)/python -c "import sysconfig; print('import site; site.addsitedir(%r)' % sysconfig.get_paths()['purelib'])" \
	  > "$$($(DOCS)/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')/lorisnb-venv.pth"
	$(DOCS)/bin/python -m pip install -r docs/requirements.txt
	$(DOCS)/bin/python -m pip install --no-deps django-static-mathjax==3.2.2.1
	touch $@

# the manual, built offline with warnings as errors and the notebooks executed, into $(DOCS_OUT)/
docs: $(DOCS_STAMP) bytecode
	PATH="$(abspath $(DOCS))/bin:$(abspath $(BIN)):$$PATH" $(DOCS)/bin/python docs/build.py "$(DOCS_OUT)"
