# Two commands for users: `make demo` and `make test`. Both create .venv on first use.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test bench lock clean

# CI installs the exact versions of requirements-ci.lock (.ci/run sets PIP_CONSTRAINTS); elsewhere the
# lower bounds of pyproject.toml apply.  A constraints file pins versions, it never adds packages.
PIP_CONSTRAINTS ?=
CONSTRAINTS := $(if $(PIP_CONSTRAINTS),-c $(PIP_CONSTRAINTS))

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip $(CONSTRAINTS)
	$(BIN)/python -m pip install --quiet -e '.[test,eval]' $(CONSTRAINTS)
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/chronav demo

# The unit tests (single-process, ~1,500) run in two workers, one per core: ~2 min instead of ~4.
# Everything outside tests/unit (integration and system tests) then runs in two workers too, one
# test FILE per worker at a time (--dist loadfile: a module's fixture run stays in one process):
# those start routers and agent processes, which use ~1.2 cores on average, so two files side by
# side fill both cores; measured on the 2-core machine, 505 s instead of 684 s serially, every test
# passing (their timeouts are bounds on a loaded machine, not speed goals).  The files go out longest
# first (tests/conftest.py LONGEST_FIRST; --no-loadscope-reorder keeps that order, where xdist would
# send the files with the most tests first and leave the long single-launch files to one worker at
# the end).  Both phases print their 15 slowest tests, so CI's log shows where the time goes.
# Both phases always run; make fails if either failed.
# Before them: import layers, lint (ruff, ~0.2 s) and types (mypy on the library layers; ~10 s cold,
# under 1 s warm from its cache in .venv/mypy_cache). Rules and scope: pyproject.toml, docs/code_health.md.
test: $(STAMP)
	$(BIN)/lint-imports
	$(BIN)/ruff check .
	$(BIN)/mypy
	$(BIN)/python -m pytest -q -p no:cacheprovider --durations=15 -n 2 tests/unit; unit=$$?; \
	$(BIN)/python -m pytest -q -p no:cacheprovider --durations=15 -n 2 --dist loadfile --no-loadscope-reorder \
		tests --ignore=tests/unit; rest=$$?; \
	test $$unit -eq 0 && test $$rest -eq 0

bench: $(STAMP)
	$(BIN)/python tools/bench/bench_dsr.py
	$(BIN)/python tools/bench/bench_dsr_decode.py
	$(BIN)/python tools/bench/bench_planner.py
	$(BIN)/python tools/bench/bench_planner_symbolic.py
	$(BIN)/python tools/bench/bench_day.py
	$(BIN)/python tools/bench/bench_evaluate.py

# After a dependency change: requirements-ci.lock again, from a fresh venv of .[test,eval].
lock:
	rm -rf .lock-venv && $(PYTHON) -m venv .lock-venv
	.lock-venv/bin/python -m pip install --quiet --upgrade pip
	.lock-venv/bin/python -m pip install --quiet '.[test,eval]'
	{ echo "# CI constraints (make lock): pip freeze of a fresh venv of .[test,eval], $$(.lock-venv/bin/python -V)"; \
	  .lock-venv/bin/python -m pip freeze --all --exclude chronav --exclude setuptools; } > requirements-ci.lock
	rm -rf .lock-venv build

clean:
	rm -rf $(VENV) recordings/*.rrd recordings/*/rrd
