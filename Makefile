# Set-up and entry points. `make demo` and `make test` work on a fresh machine: they create
# .venv, install the package with the dependency versions that were tested (requirements.lock),
# then run.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp

.PHONY: setup lock browser terminal demo test checks test-kernels test-fast lint types bench bench-long clean

setup: $(STAMP)

$(STAMP): pyproject.toml setup.py requirements.lock
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -c requirements.lock -e '.[test]'
	touch $(STAMP)

# requirements.lock: every dependency of the package and its test extra, pinned, resolved by uv
# from pyproject.toml. Refresh it after changing a dependency (pins already in the file are kept
# where they still fit; `make lock UPGRADE=--upgrade` takes the newest allowed), then run
# `make test` on the new versions before committing it.
lock: setup
	$(VENV)/bin/uv pip compile pyproject.toml --extra test --python-version 3.11 $(UPGRADE) \
		--no-header --output-file requirements.lock

# The paper's controller: TWIL + WAM to a goal pose, the summary, a figure and an HTML replay in runs/.
demo: setup
	$(PY) -m twil_control.demo

# The browser tests drive Debian's Chromium through its ChromeDriver (the view's tests).
BROWSER := /usr/bin/chromedriver
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

browser: $(BROWSER)

$(BROWSER):
	$(SUDO) apt-get update -qq
	DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq chromium chromium-driver

# The keyboard teleop tests type into a real terminal: Debian's tmux.
TMUX := /usr/bin/tmux

terminal: $(TMUX)

$(TMUX):
	$(SUDO) apt-get update -qq
	DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq tmux

# What CI runs: the whole suite, long end-to-end runs included, in two parts. First the compiled
# kernels' own tests (marker `kernels`), beside apt, lint (ruff, the layout, the import contracts)
# and types (pyright's basic checks through basedpyright, which brings its own Node.js from PyPI):
# numba compiles the kernels there, into its cache beside the source, instead of every worker and
# launch of the long runs compiling them side by side on a fresh checkout. Then every other test.
# Both parts on two workers (pytest-xdist; each test file on one worker, so a file's fixtures are
# built once).
XDIST := -n 2 --dist loadfile

test: setup
	$(MAKE) --no-print-directory --output-sync=target -j2 checks test-kernels
	$(PY) -m pytest -m "(slow or not slow) and not kernels" $(XDIST)

# One after another: the two apt-get installs would wait on each other's dpkg lock.
checks:
	env -u MAKEFLAGS $(MAKE) --no-print-directory browser terminal lint types

test-kernels: setup
	$(PY) -m pytest -m kernels $(XDIST)

lint: setup
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	$(VENV)/bin/lint-imports

types: setup
	$(VENV)/bin/basedpyright

# Lint and the fast selection of the suite (plain `pytest` runs the same tests).
test-fast: setup lint
	$(PY) -m pytest

bench: setup browser
	$(PY) bench/run_all.py

bench-long: setup browser
	$(PY) bench/run_all.py --long

clean:
	rm -rf $(VENV) build src/*.egg-info .pytest_cache
