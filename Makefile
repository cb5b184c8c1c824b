# uvsim: the two quick-start commands are `make demo` and `make test`.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
BASE   := $(VENV)/.installed-base
TEST   := $(VENV)/.installed-test

.PHONY: demo test test-all bench clean

$(BASE): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[fast]"
	touch $(BASE)

$(TEST): $(BASE)
	$(PY) -m pip install --quiet -e ".[test]"
	touch $(TEST)

demo: $(BASE)
	$(VENV)/bin/uvsim demo --out demo_output

test: $(TEST)
	$(PY) -m pytest -q

test-all: $(TEST)
	$(PY) -m pytest -q -m "slow or not slow"

bench: $(BASE)
	$(VENV)/bin/uvsim bench

clean:
	rm -rf $(VENV) demo_output .pytest_cache
