# The two commands of the README, each bootstrapping .venv itself:
#   make demo   the course tour: figures, animations and tables into out/
#   make test   the whole test suite
# and `make lab` to open the course folder (lectures/ and exercises/) in Jupyter Lab.

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
OUT    ?= out

.PHONY: demo test kernels lab bench clean

# Packages are installed by uv (`make INSTALLER=pip ...` for pip alone): on a fresh clone uv installed
# .[dev,fast] and wrote their bytecode in 16 s where pip took 31 s (2026-12-07, the 2-core machine). Where uv
# cannot be installed or cannot install (it reads no pip.conf: a private index), pip does the install.
INSTALLER ?= uv

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	[ "$(INSTALLER)" != uv ] || $(BIN)/python -m pip install --quiet uv || echo "uv could not be installed: pip installs"

# Installs the target's PACKAGES: uv if it is there, with the bytecode (every process imports the packages, and
# where PYTHONDONTWRITEBYTECODE is set none would write it), else pip (which writes it itself)
INSTALL = { [ "$(INSTALLER)" = uv ] && [ -x $(BIN)/uv ] && $(BIN)/uv pip install --quiet --compile-bytecode \
	--python $(BIN)/python $(PACKAGES); } || $(BIN)/python -m pip install --quiet $(PACKAGES)

# Stamp files record which extras are installed; they are redone when
# pyproject.toml changes.
$(VENV)/.installed: PACKAGES = -e .
$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(INSTALL)
	touch $@

$(VENV)/.installed-dev: PACKAGES = -e '.[dev,fast]'
$(VENV)/.installed-dev: pyproject.toml | $(BIN)/python
	$(INSTALL)
	touch $@ $(VENV)/.installed

$(VENV)/.installed-lab: PACKAGES = -e '.[lab]'
$(VENV)/.installed-lab: pyproject.toml | $(BIN)/python
	$(INSTALL)
	touch $@ $(VENV)/.installed

# The package's bytecode, written here: where PYTHONDONTWRITEBYTECODE is set (as in some containers) no
# process writes it, and every process that imports particles (each grading worker, each notebook kernel)
# would compile the sources again. Only the files changed since the last time are compiled.
BYTECODE = $(BIN)/python -m compileall -q -j 0 particles tests bench

demo: $(VENV)/.installed
	$(BYTECODE)
	$(BIN)/particles tour --out $(OUT)

# System tools the tests need (headless Chromium for the course-site tests, PHP for the Moodle import), installed once, here,
# before any test runs: never by test workers racing for the package manager's lock
$(VENV)/.system-tools: .ci/install-system-tools | $(BIN)/python
	sh .ci/install-system-tools
	touch $@

# numba's kernels, compiled once into the disk cache by two processes (57-75 s on a fresh clone, 2 s
# after): without it both test workers, and the notebooks they start, compile the same kernels. Only a
# speed-up: if it fails, the tests compile what they use, as before
kernels: $(VENV)/.installed-dev
	$(BYTECODE)
	$(BIN)/particles warm --jobs 2 || echo "particles warm failed: the tests will compile the kernels they use"

# the set-up's two long parts side by side: the system tools (apt-get: the network and the disk, on a
# fresh machine) while the kernels compile (the CPU); then two workers (pytest-xdist), a test file per
# worker at a time: module fixtures (a graded corpus) run once
test:
	$(MAKE) --no-print-directory -j 2 $(VENV)/.system-tools kernels
	$(BIN)/python -m pytest -n 2 --dist loadfile

lab: $(VENV)/.installed-lab
	$(BIN)/jupyter lab .

bench: $(VENV)/.installed
	for b in bench/bench_*.py; do $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) $(OUT) *.egg-info
