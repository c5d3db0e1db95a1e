# fourws: `make demo` and `make test` are all a newcomer needs (see README.md).
SHELL := /bin/bash
.SHELLFLAGS := -o pipefail -c
# pip prints one harmless warning per package about a local index that does not exist here
QUIET := 2>&1 | { grep -v "^WARNING: Location" || true; }
VENV ?= .venv
PY := $(VENV)/bin/python
PIP := $(VENV)/bin/pip
STAMP := $(VENV)/.fourws-setup-done

.PHONY: setup test demo bench clean

setup: $(STAMP)

$(STAMP): requirements.txt setup.py Makefile
	@command -v python3 >/dev/null || { echo "python3 missing: apt-get install python3 python3-venv"; exit 1; }
	@if ! command -v cmake >/dev/null || ! command -v g++ >/dev/null || ! python3 -c "import ensurepip" 2>/dev/null; then \
	  echo "installing cmake, g++ and python3-venv from Debian"; \
	  apt-get update -qq && apt-get install -y -qq cmake g++ python3-venv python3-dev >/dev/null; fi
	test -x $(PY) || python3 -m venv $(VENV)
	$(PIP) install -q --upgrade pip $(QUIET)
	$(PIP) install -q -r requirements.txt $(QUIET)
	$(PIP) install -q --no-deps -e . $(QUIET)
	touch $(STAMP)

test: setup
	$(PY) -m pytest -q test

demo: setup
	$(VENV)/bin/fourws demo

bench: setup
	$(VENV)/bin/fourws bench --json

clean:
	rm -rf build install log runs report
