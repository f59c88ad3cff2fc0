# Set-up and entry points. `make demo` and `make test` work on a fresh machine: they create
# .venv, install the package with its pinned dependencies, then run.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp

.PHONY: setup browser terminal demo test test-fast bench bench-long clean

setup: $(STAMP)

$(STAMP): setup.py
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

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

# The whole suite, long end-to-end runs included (what CI runs).
test: setup browser terminal
	$(PY) -m pytest -m "slow or not slow"

# The fast selection (plain `pytest` does the same).
test-fast: setup
	$(PY) -m pytest

bench: setup browser
	$(PY) bench/run_all.py

bench-long: setup browser
	$(PY) bench/run_all.py --long

clean:
	rm -rf $(VENV) build src/*.egg-info .pytest_cache
