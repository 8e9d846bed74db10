# The whole set-up on a fresh machine with Python 3.11: `make demo` and `make test`.
# Both create (or refresh, when pyproject.toml changes) the virtual environment in .venv.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

demo: $(STAMP)
	mkdir -p demo
	$(BIN)/toonmotion sample -o demo/hero.png --skeleton demo/hero.json
	$(BIN)/toonmotion rig demo/hero.png --skeleton demo/hero.json -o demo/hero
	$(BIN)/toonmotion show demo/hero -o demo/overview.png

test: $(STAMP)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/python -m pytest

bench: $(STAMP)
	$(BIN)/python benchmarks/rig.py

clean:
	rm -rf $(VENV) demo
