# Everything is set up on first use in .venv (Python >= 3.11); nothing else is needed.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e ".[test]"
	touch $(STAMP)

## demo: run the main demo graph headless, writing a Rerun recording under out/
demo: $(STAMP)
	$(BIN)/dgraph run graphs/pd_double_integrator.yaml --rerun save out/pd_double_integrator.rrd --npz out/pd_double_integrator.npz

## test: lint, then the whole test suite
test: $(STAMP) lint
	$(BIN)/python -m pytest

lint: $(STAMP)
	$(BIN)/ruff check .

## bench: signal-overhead benchmark (installs the Drake peer in .venv-bench)
bench: $(STAMP)
	bash bench/setup_peer.sh
	$(BIN)/python bench/signal_overhead.py --peer .venv-bench/bin/python

clean:
	rm -rf $(VENV) .venv-bench out .pytest_cache .hypothesis
