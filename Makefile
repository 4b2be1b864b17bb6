# Two commands for users: `make demo` and `make test`. Both create .venv on first use.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test bench clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,eval]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/chronav demo

test: $(STAMP)
	$(BIN)/lint-imports
	$(BIN)/python -m pytest -q -p no:cacheprovider

bench: $(STAMP)
	$(BIN)/python tools/bench_dsr.py
	$(BIN)/python tools/bench_dsr_decode.py
	$(BIN)/python tools/bench_planner.py
	$(BIN)/python tools/bench_planner_symbolic.py
	$(BIN)/python tools/bench_day.py
	$(BIN)/python tools/bench_evaluate.py

clean:
	rm -rf $(VENV) recordings/*.rrd
