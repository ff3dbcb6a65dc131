# Two entry points (see README): `make report` (the batch report on the bundled data) and
# `make test`. Both create or refresh the local virtual environment .venv first.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp
export PATH := $(abspath $(BIN)):$(PATH)
export MPLBACKEND ?= Agg

.PHONY: report test evaluate bench lint clean-venv

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip
	$(BIN)/python -m pip install -e '.[dev]'
	touch $(STAMP)

report: $(STAMP)
	$(BIN)/lorisnb report

evaluate: $(STAMP)
	$(BIN)/lorisnb evaluate --scale auto --csv results/evaluate.csv $(or $(DATA),../shared/data)/openloris-scene/icra20_results

test: $(STAMP)
	$(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/python benchmarks/bench.py

lint: $(STAMP)
	$(BIN)/ruff check lorisnb tests benchmarks

clean-venv:
	rm -rf $(VENV)
