# Two entry points (see README): `make report` (the batch report on the bundled data) and
# `make test`. Both create or refresh the local virtual environment .venv first.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp
export PATH := $(abspath $(BIN)):$(PATH)
export MPLBACKEND ?= Agg

.PHONY: report test test-fast test-slow test-browser browser-deps lint format evaluate bench bytecode clean-venv

$(STAMP): pyproject.toml lorisnb/_version.py
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

# everything: fast tests, then the slow ones (notebooks, reports, the installed wheel)
test: bytecode
	$(BIN)/python -m pytest -q -m "not browser"

test-fast: bytecode
	$(BIN)/python -m pytest -q -m "not slow and not browser"

test-slow: bytecode
	$(BIN)/python -m pytest -q -m "slow and not browser"

# Debian's Chromium and its driver (apt, as root or with sudo), where missing
browser-deps:
	@command -v chromium >/dev/null && command -v chromedriver >/dev/null || { \
	  SUDO=$$(test "$$(id -u)" = 0 || echo sudo); \
	  $$SUDO apt-get update -qq && $$SUDO apt-get install -y -qq chromium chromium-driver; }

# the notebooks in JupyterLab in headless Chromium (screenshots in results/browser/)
test-browser: $(STAMP) browser-deps
	$(BIN)/python -m pytest -q -m browser

lint: $(STAMP)
	$(BIN)/ruff check lorisnb tests benchmarks notebooks
	$(BIN)/ruff format --check lorisnb tests benchmarks notebooks
	$(BIN)/mypy
	$(BIN)/lint-imports

format: $(STAMP)
	$(BIN)/ruff format lorisnb tests benchmarks notebooks
	$(BIN)/ruff check --fix lorisnb tests benchmarks notebooks

bench: bytecode
	$(BIN)/python benchmarks/bench.py

clean-venv:
	rm -rf $(VENV)
