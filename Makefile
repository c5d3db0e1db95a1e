# fourws: `make demo` and `make test` are all a newcomer needs (see README.md).
SHELL := /bin/bash
VENV ?= .venv
PY := $(VENV)/bin/python
PIP := $(VENV)/bin/pip
STAMP := $(VENV)/.fourws-setup-done

.PHONY: setup test demo bench clean

setup: $(STAMP)

$(STAMP): requirements.txt setup.py Makefile
	@command -v python3 >/dev/null || { echo "python3 missing: apt-get install python3 python3-venv"; exit 1; }
	@command -v cmake >/dev/null && command -v g++ >/dev/null || \
	  { echo "installing cmake and g++ from Debian"; apt-get update -qq && apt-get install -y -qq cmake g++ python3-venv >/dev/null; }
	test -x $(PY) || python3 -m venv $(VENV)
	$(PIP) install -q --upgrade pip 2>&1 | grep -v "^WARNING: Location" || true
	$(PIP) install -q -r requirements.txt 2>&1 | grep -v "^WARNING: Location" || true
	$(PY) -c "import rclpy, numpy, scipy, numba" # fail here if the install did not work
	$(PIP) install -q --no-deps -e . 2>&1 | grep -v "^WARNING: Location" || true
	touch $(STAMP)

test: setup
	$(PY) -m pytest -q test

demo: setup
	$(VENV)/bin/fourws demo

bench: setup
	$(VENV)/bin/fourws bench --json

clean:
	rm -rf build install log runs report
