# Two entry points: `make demo` (the main job) and `make test` (the whole suite).
# Both bootstrap a local virtual environment in .venv from the package registry.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test lint typecheck unit clean generate

# The install takes about 80 s the first time: pip says what it collects, downloads and
# installs (no --quiet, so that the wait is visible; its progress bars show on a terminal).
# Upgrading pip itself takes seconds and stays quiet.
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install -e '.[dev]'
	touch $(STAMP)

DEMO_OUT ?= out/demo

# The main job: the published baseline (proximity) against urgency-aware selection
# (alpha = 0.7 and 9), 100 runs of 3 robots / 7 carriers on the calibrated paper-sim
# profile: KPI table with CIs and p-values, the choice statistics under it, the event
# log and event table, a snapshot and an animation of run 0 per condition; then the
# quick reproduction of all five published studies and its HTML report.
demo: $(STAMP)
	mkdir -p $(DEMO_OUT)
	$(BIN)/swarmtag simulate --runs 100 --condition proximity --condition urgency:alpha=0.7 \
		--condition urgency:alpha=9 --events $(DEMO_OUT)/events.csv \
		--event-table $(DEMO_OUT)/event-table.csv --snapshot $(DEMO_OUT)/snapshot.png \
		--animate $(DEMO_OUT)/run.gif
	$(BIN)/swarmtag reproduce --quick --out $(DEMO_OUT)/reproduction

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks examples
	$(BIN)/ruff format --check src tests benchmarks examples

typecheck: $(STAMP)
	$(BIN)/mypy

# One pytest worker per logical core (at most 8; psutil may count two vCPUs as one physical core);
# tests/conftest.py compiles the fast kernel first. Tests that bound seconds run alone after.
unit: $(STAMP)
	$(BIN)/pytest --numprocesses logical --maxprocesses 8 --dist worksteal -m "not serial"
	$(BIN)/pytest -m serial

test: lint typecheck unit

# The typed parameter records derived from the parameter schema (docs/architecture.md,
# "How to add a mechanic"); tests/sim/model/test_kernel_parameters.py fails while they are stale.
generate: $(STAMP)
	$(BIN)/python -c "from swarmtag.sim.model.kernel_parameters import main; main()"

clean:
	rm -rf $(VENV) .mypy_cache .pytest_cache .ruff_cache .hypothesis
