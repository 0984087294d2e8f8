# The two commands of the README, each bootstrapping .venv itself:
#   make demo   the course tour: figures, animations and tables into out/
#   make test   the whole test suite
# and `make lab` to open the course folder (lectures/ and exercises/) in Jupyter Lab.

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
OUT    ?= out

.PHONY: demo test lab bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# Stamp files record which extras are installed; they are redone when
# pyproject.toml changes.
$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e .
	touch $@

$(VENV)/.installed-dev: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[dev,fast]'
	touch $@ $(VENV)/.installed

$(VENV)/.installed-lab: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[lab]'
	touch $@ $(VENV)/.installed

demo: $(VENV)/.installed
	$(BIN)/particles tour --out $(OUT)

# System tools the tests need (headless Chromium for the course-site tests), installed once, here,
# before any test runs: never by test workers racing for the package manager's lock
$(VENV)/.system-tools: .ci/install-system-tools | $(BIN)/python
	sh .ci/install-system-tools
	touch $@

# two workers (pytest-xdist), a test file per worker at a time: module fixtures (a graded corpus) run once
test: $(VENV)/.installed-dev $(VENV)/.system-tools
	$(BIN)/python -m pytest -n 2 --dist loadfile

lab: $(VENV)/.installed-lab
	$(BIN)/jupyter lab .

bench: $(VENV)/.installed
	for b in bench/bench_*.py; do $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) $(OUT) *.egg-info
