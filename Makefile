# fourws: `make demo` and `make test` are all a newcomer needs (see README.md).
SHELL := /bin/bash
.SHELLFLAGS := -o pipefail -c
# pip prints one harmless warning per package about a local index that does not exist here
QUIET := 2>&1 | { grep -v "^WARNING: Location" || true; }
VENV ?= .venv
PY := $(VENV)/bin/python
PIP := $(VENV)/bin/pip
STAMP := $(VENV)/.fourws-setup-done
MSGS_STAMP := $(VENV)/.fourws-msgs-done
MSGS_BUILD := build/venv-fourws_msgs

.PHONY: setup test demo bench clean

setup: $(STAMP) $(MSGS_STAMP)

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

# fourws_msgs (ament_cmake interface package) built against the ROS wheels, installed into the
# venv prefix so the generated messages import with no extra environment. Rebuilt when a .msg
# or the package files change (or after the venv was reinstalled).
$(MSGS_STAMP): $(STAMP) $(wildcard msg/*.msg) fourws_msgs/CMakeLists.txt fourws_msgs/package.xml
	rm -rf $(MSGS_BUILD) && mkdir -p $(MSGS_BUILD)
	V=$(abspath $(VENV)); PATH=$$V/bin:$$PATH CMAKE_PREFIX_PATH=$$V AMENT_PREFIX_PATH=$$V \
	  cmake -S fourws_msgs -B $(MSGS_BUILD) -DCMAKE_INSTALL_PREFIX=$$V \
	  -DPython3_EXECUTABLE=$$V/bin/python -DBUILD_TESTING=OFF >$(MSGS_BUILD)/build.log 2>&1 \
	  && PATH=$$V/bin:$$PATH cmake --build $(MSGS_BUILD) -j2 >>$(MSGS_BUILD)/build.log 2>&1 \
	  && cmake --install $(MSGS_BUILD) >>$(MSGS_BUILD)/build.log 2>&1 \
	  || { tail -30 $(MSGS_BUILD)/build.log; echo "fourws_msgs build failed, log: $(MSGS_BUILD)/build.log"; exit 1; }
	cd /tmp && $(abspath $(PY)) -c "from fourws_msgs.msg import VehicleState" # fail here if not importable
	touch $(MSGS_STAMP)

test: setup
	$(PY) -m pytest -q test

demo: setup
	$(VENV)/bin/fourws demo

bench: setup
	$(VENV)/bin/fourws bench --json

clean:
	rm -rf build install log runs report
