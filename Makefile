# Everything is set up on first use in .venv (Python >= 3.11); nothing else is needed.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test test-fast lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e ".[test]"
	touch $(STAMP)

## demo: TALOS sways 20 s in MuJoCo (headless), writing out/talos_sway.rrd and .npz
demo: $(STAMP)
	$(BIN)/dgraph run graphs/talos_sway.yaml --save out/talos_sway.rrd --npz out/talos_sway.npz

## test: lint, then the whole test suite, one pytest worker per CPU (a test file's tests stay on one worker, so
## they share its module fixtures, the simulations run once)
PYTEST := $(BIN)/python -m pytest -n logical --dist loadfile

test: $(STAMP) lint
	$(PYTEST)

## test-fast: the developer's loop, everything but the closed-loop TALOS simulations (marker `sim`)
test-fast: $(STAMP) lint
	$(PYTEST) -m "not sim"

lint: $(STAMP)
	$(BIN)/ruff check .

## bench: signal overhead against Drake, TALOS tick against TSID 1.10 (with the acceptance of the tick issue and the
## demo's speed-up over ddec0a5), where the demo's time goes (py-spy), ID formulations, sole wrenches or corner
## forces, energy tank (installs the peers)
bench: $(STAMP)
	$(BIN)/pip install --quiet -e ".[bench]"
	bash bench/setup_peer.sh
	$(BIN)/python bench/signal_overhead.py --peer .venv-bench/bin/python
	bash bench/setup_tsid.sh
	$(BIN)/python bench/talos_tick.py --ticks 3000 --rounds 3 --base ddec0a5 --json out/talos_tick.json
	$(BIN)/python bench/profile_shares.py --json out/profile_shares.json
	$(BIN)/python bench/id_formulations.py
	$(BIN)/python bench/contact_forces.py --json out/contact_forces.json
	$(BIN)/pip install --quiet -e ".[plots]"
	$(BIN)/python bench/energy_tank.py --plots docs

clean:
	rm -rf $(VENV) .venv-bench .venv-tsid .venv-lower out .pytest_cache .hypothesis
