# Two entry points: `make demo` (the main job) and `make test` (the whole suite).
# Both bootstrap a local virtual environment in .venv from the package registry.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test lint typecheck unit clean generate

WARMUP_LOG := $(VENV)/kernel-warmup.log
DEMO_STAMP := $(VENV)/.installed-demo

# The package's bytecode is written once at the install (compileall writes it even where
# PYTHONDONTWRITEBYTECODE is set): every swarmtag command, and each one the tests start, then
# reads it instead of compiling the sources again (a quarter second a command).
# The fast simulation kernel is compiled once per machine (about 1 min for its first entry
# point, on two processes: its last phases compile beside the rest). numba and numpy are
# installed first, alone, with pyproject.toml's bounds (about 6 s against 11 s for the package's
# whole core; the later installs then leave them as they are), and the compilation starts in the
# background at once, from the sources (PYTHONPATH: swarmtag is installed after it), so that it
# overlaps the rest of the install (and, for make test, ruff and mypy); `demo` and `unit` wait
# for it. Entry points: batched (every command) and split (one run over threads; the tests),
# which starts once batched has cached the code they share (tests/kernel_warmup.py). The
# bootstrap's compiled loops (statistics, a few seconds) need scipy: they compile once the
# core is installed, while the kernel goes on compiling.
# The warm-up holds a lock in numba's cache folder while it runs: `demo` waits for it there
# (--wait), and the tests' own warm-up (tests/conftest.py) waits for it while pytest collects.
define install_with_warmup
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install $$($(BIN)/python -m tests.kernel_warmup --requirements)
	@echo "make: compiling the fast simulation kernel ($(1)) in the background; log: $(WARMUP_LOG)"
	@PYTHONPATH='$(CURDIR)/src' $(BIN)/python -m tests.kernel_warmup $(1) > $(WARMUP_LOG) 2>&1 &
	$(2) $(BIN)/python -m pip install -e '.[fast]'
	$(2) $(BIN)/python -m compileall -q src
	$(2) $(BIN)/python -m tests.kernel_warmup statistics
endef

# The demo's install runs at a lower priority beside the kernel's compilation, which the demo
# waits for: the compilation gets the cores first (the first make demo 88-91 s -> 83 s). Not
# the tests': their install, ruff and mypy are as long as the compilation, and must end too.
BESIDE := nice -n 10

WAIT_FOR_WARMUP = @$(BIN)/python -m tests.kernel_warmup --wait

# The install takes about 80 s the first time: pip says what it collects, downloads and
# installs (no --quiet, so that the wait is visible; its progress bars show on a terminal).
# Upgrading pip itself takes seconds and stays quiet. The demo needs fewer extras than the
# tests; the test install covers the demo's.
$(DEMO_STAMP): pyproject.toml
	$(call install_with_warmup,batched,$(BESIDE))
	$(BESIDE) $(BIN)/python -m pip install -e '.[fast,plot,experiments]'
	touch $@

$(STAMP): pyproject.toml
	$(call install_with_warmup,batched split,)
	$(BIN)/python -m pip install -e '.[dev]'
	touch $@ $(DEMO_STAMP)

DEMO_OUT ?= out/demo

# The main job: the published baseline (proximity) against urgency-aware selection
# (alpha = 0.7 and 9), 100 runs of 3 robots / 7 carriers on the calibrated paper-sim
# profile: KPI table with CIs and p-values, the choice statistics under it, the event
# log and event table, a snapshot and an animation of run 0 per condition; then the
# quick reproduction of all five published studies and its HTML report.
demo: $(DEMO_STAMP)
	$(WAIT_FOR_WARMUP)
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
# tests/conftest.py has the fast kernel compiled (or waits for the install's warm-up) while
# pytest collects, and starts the tests once it is in. Tests that bound seconds run alone after.
# Each part ends with its slowest tests (--durations), so every run shows where the time goes.
# Bytecode is written during the tests even where PYTHONDONTWRITEBYTECODE is set: pytest keeps
# its rewritten test modules (collecting all of them takes 12 s a process without, 7 s with).
# The console's browser tests drive the system's Chromium (.ci/run installs it as root).
CHROMIUM ?= /usr/bin/chromium

unit: $(STAMP)
	@test -x $(CHROMIUM) || { echo "make test needs Chromium at $(CHROMIUM) for the console's browser tests: run 'apt-get install -y chromium' as root (.ci/run does)"; exit 1; }
	PYTHONDONTWRITEBYTECODE= $(BIN)/pytest --numprocesses logical --maxprocesses 8 --dist worksteal -m "not serial" --durations=30
	PYTHONDONTWRITEBYTECODE= $(BIN)/pytest -m serial --durations=10

test: lint typecheck unit

# The typed parameter records derived from the parameter schema (docs/architecture.md,
# "How to add a mechanic"); tests/sim/model/test_kernel_parameters.py fails while they are stale.
generate: $(STAMP)
	$(BIN)/python -c "from swarmtag.sim.model.kernel_parameters import main; main()"

clean:
	rm -rf $(VENV) .mypy_cache .pytest_cache .ruff_cache .hypothesis
