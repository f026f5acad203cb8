# Two commands do all the set-up on a fresh machine with Python 3.11:
#   make demo   - create .venv, install camdyn, run the demonstration (prints results, writes out/)
#   make test   - create .venv, install camdyn with test extras, check style (ruff) and layers
#                 (import-linter), run the test suite
PYTHON ?= python3
VENV ?= .venv
BIN = $(VENV)/bin

$(BIN)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $@

.PHONY: demo test bench install clean mutation
install: $(BIN)/.installed

demo: $(BIN)/.installed
	$(BIN)/camdyn demo --out out

test: $(BIN)/.installed
	$(BIN)/ruff check src tests tools benchmarks examples
	$(BIN)/lint-imports
	$(BIN)/python -m pytest -q

# deliberate physics mistakes (tools/mutation_check.py) must make a fast test subset fail
mutation: $(BIN)/.installed
	$(BIN)/python tools/mutation_check.py

bench: $(BIN)/.installed
	$(BIN)/python benchmarks/bench_simulate.py
	$(BIN)/python benchmarks/bench_identify.py

clean:
	rm -rf $(VENV) out .pytest_cache
