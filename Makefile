# Two set-up commands for a fresh machine with Python >= 3.10 and git:
#   make run    installs into .venv and runs the default scenario end to end on python-can's virtual bus
#   make test   installs into .venv (with test extras) and runs the test suite
PYTHON ?= python3
VENV ?= .venv
SCENARIO ?= scenarios/highway_cut_in.yaml

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --upgrade pip
	$(VENV)/bin/python -m pip install --quiet -e '.[test]'
	touch $@

.PHONY: install run test bench dbc
install: $(VENV)/.installed

run: $(VENV)/.installed
	$(VENV)/bin/radarnode run $(SCENARIO)

test: $(VENV)/.installed
	$(VENV)/bin/python -m pytest -q -n auto

bench: $(VENV)/.installed
	$(VENV)/bin/python benchmarks/wire.py

# the whole-bus DBC is generated from dbc/ars408.dbc and dbc/radarnode.dbc (tests/test_bus_dbc.py checks it)
dbc: $(VENV)/.installed
	$(VENV)/bin/python -m radarnode.wire.busdbc > dbc/radarnode_bus.dbc.tmp && mv dbc/radarnode_bus.dbc.tmp dbc/radarnode_bus.dbc
