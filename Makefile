# The two commands a newcomer needs; each sets up .venv on first use.
VENV ?= .venv
BIN := $(VENV)/bin

.PHONY: demo test test-fast lint bench system-deps clean clean-compiled

$(VENV)/.installed: pyproject.toml
	python3 -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q -e '.[test]'
	touch $@

## Solve the two-cube opaque instance (Table 1 P2) and show its policy.
demo: $(VENV)/.installed
	$(BIN)/ehatp solve examples/cubes/p2.toml --out p2.policy.json
	$(BIN)/ehatp show p2.policy.json
	@echo
	@echo "ehatp is installed in $(VENV). To type 'ehatp ...' as the README does, run this once in"
	@echo "each new shell (or call $(BIN)/ehatp):"
	@echo
	@echo "    . $(VENV)/bin/activate"

## Run the whole test suite, slow tests, ruff and mypy included (what CI runs), on every core.
test: $(VENV)/.installed
	$(BIN)/python -m pytest -n auto

## The loop while editing: every test not marked slow, on every core (about a minute on two).
test-fast: $(VENV)/.installed
	$(BIN)/python -m pytest -m "not slow" -n auto

## ruff and mypy alone.
lint: $(VENV)/.installed
	$(BIN)/ruff check src tests benchmarks examples
	$(BIN)/mypy

## Reproduce Table 1 with timings.
bench: $(VENV)/.installed
	$(BIN)/ehatp bench table1

## The BehaviorTree.CPP tick program tests/test_bt_cpp.py runs, built into ~/.cache/ehatp-btcpp
## against an installed BehaviorTree.CPP 4 (benchmarks/bt_cpp.py says where it looks); not in CI.
.PHONY: bt-cpp
bt-cpp:
	python3 benchmarks/bt_cpp.py

## Debian packages some tests use (Graphviz for SVG, Chromium for the explorer, a C compiler and
## Python's headers for the compiled core's build); needs root.
system-deps:
	apt-get update -qq && apt-get install -y -qq graphviz chromium chromium-driver build-essential python3-dev

## Remove the compiled modules a compiled build (docs/compiled.md) left beside the sources in src.
clean-compiled:
	find src \( -name '*.so' -o -name '*.pyd' \) -delete

clean: clean-compiled
	rm -rf $(VENV) p2.policy.json .pytest_cache .mypy_cache .ruff_cache .hypothesis
