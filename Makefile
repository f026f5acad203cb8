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

.PHONY: demo test bench bench-peers install clean mutation docs docs-full docs-links figures
install: $(BIN)/.installed

demo: $(BIN)/.installed
	$(BIN)/camdyn demo --out out --force

test: $(BIN)/.installed
	$(BIN)/ruff check src tests tools benchmarks examples
	$(BIN)/lint-imports
	$(BIN)/python -m pytest -q --numprocesses auto --maxprocesses 4 --dist loadfile --durations=15

# the README's and docs' figures from the current code, with the numbers each shows in
# docs/figures/figures.json (tools/make_figures.py, about 6 minutes; FIGURES_ARGS=--slow adds
# the long table and gallery scripts, about 20 minutes more)
figures: $(BIN)/.installed
	$(BIN)/python tools/make_figures.py $(FIGURES_ARGS)

# deliberate physics mistakes (tools/mutation_check.py) must make a fast test subset fail
mutation: $(BIN)/.installed
	$(BIN)/python tools/mutation_check.py

bench: $(BIN)/.installed
	$(BIN)/python benchmarks/bench_simulate.py
	$(BIN)/python benchmarks/bench_identify.py

# work-precision benchmark against compiled peers (SciPy, numbalsoda, CyRK) in its own
# virtualenv, .venv-peers: numbalsoda builds from source with gfortran, which this installs
# with apt-get where it is missing (with sudo where not root). Writes benchmarks/peers.json
# and docs/figures/work_precision.png, about 15 minutes; BENCH_PEERS_ARGS=--quick for a
# one-minute smoke check whose outputs go to the temporary directory.
PEERS_VENV ?= .venv-peers
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

$(PEERS_VENV)/bin/.installed: pyproject.toml benchmarks/requirements-peers.txt
	command -v gfortran >/dev/null || ($(SUDO) apt-get update && $(SUDO) apt-get install -y gfortran)
	$(PYTHON) -m venv $(PEERS_VENV)
	$(PEERS_VENV)/bin/python -m pip install --quiet --upgrade pip
	$(PEERS_VENV)/bin/python -m pip install --quiet -e . -r benchmarks/requirements-peers.txt
	touch $@

bench-peers: $(PEERS_VENV)/bin/.installed
	$(PEERS_VENV)/bin/python benchmarks/bench_peers.py $(BENCH_PEERS_ARGS)

# documentation site (Sphinx) in docs/_build/html: `make docs` runs the gallery scripts of
# examples/gallery/ (a few seconds each) and fails on any warning or broken internal link;
# `make docs-full` first regenerates every figure of docs/figures/ (`make figures` with the
# slow table and gallery scripts of examples/, about 25 minutes on 2 cores)
$(BIN)/.docs-installed: $(BIN)/.installed
	$(BIN)/python -m pip install --quiet -e ".[docs]"
	touch $@

docs: $(BIN)/.docs-installed
	rm -rf docs/_build/html
	$(BIN)/sphinx-build -E -W --keep-going -b html docs docs/_build/html
	$(BIN)/python tools/check_links.py docs/_build/html

# internal links and images of an existing build, offline (no `sphinx-build -b linkcheck`)
docs-links:
	$(BIN)/python tools/check_links.py docs/_build/html

docs-full: $(BIN)/.docs-installed
	$(MAKE) figures FIGURES_ARGS=--slow
	$(MAKE) docs

clean:
	rm -rf $(VENV) out .pytest_cache docs/_build docs/api docs/auto_examples
