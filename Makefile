# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
# fourws: `make demo` and `make test` are all a newcomer needs (see README.md).
SHELL := /bin/bash
.SHELLFLAGS := -o pipefail -c
# pip prints one harmless warning per package about a local index that does not exist here
QUIET := 2>&1 | { grep -v "^WARNING: Location" || true; }
VENV ?= .venv
PY := $(VENV)/bin/python
PIP := $(VENV)/bin/pip
# the versions the tests passed with (`make lock` refreshes it from a clean install)
LOCK := requirements.lock
STAMP := $(VENV)/.fourws-setup-done
MSGS_STAMP := $(VENV)/.fourws-msgs-done
KERNELS_STAMP := $(VENV)/.fourws-kernels-done
MSGS_BUILD := build/venv-interfaces
# interface packages no ROS wheel provides, built before fourws's own (interfaces/SOURCE.md)
VENDORED_INTERFACES := interfaces/tf2_msgs interfaces/ackermann_msgs
LOCK_VENV := build/lock-venv

.PHONY: setup test demo bench lock clean

setup: $(STAMP) $(MSGS_STAMP) $(KERNELS_STAMP)
	@# fourws's own bytecode, compiled here (at once when it is up to date): every process of
	@# a run imports about 80 fourws modules, and where Python writes no bytecode itself
	@# (PYTHONDONTWRITEBYTECODE, a read-only checkout) it compiled them anew in each (0.2 s)
	@$(PY) -m compileall -q $(wildcard fourws_*) >/dev/null

# One line per stage; the stage's own output goes to the terminal only when it fails.
$(STAMP): requirements.txt $(LOCK) setup.py Makefile
	@command -v python3 >/dev/null || { echo "python3 missing: apt-get install python3 python3-venv"; exit 1; }
	@if ! command -v cmake >/dev/null || ! command -v g++ >/dev/null || ! python3 -c "import ensurepip" 2>/dev/null \
	    || ! command -v node >/dev/null || ! command -v npm >/dev/null; then \
	  echo "setup 1/5: installing cmake, g++, python3-venv and nodejs/npm (the live-view test's client) from Debian"; \
	  apt-get update -qq && apt-get install -y -qq cmake g++ python3-venv python3-dev nodejs npm >/dev/null; \
	else echo "setup 1/5: cmake, g++, python3-venv and nodejs/npm are installed"; fi
	@echo "setup 2/5: Python packages into $(VENV), versions from $(LOCK) (about 1 min the first time)"
	@test -x $(PY) || python3 -m venv $(VENV)
	@$(PIP) install -q --upgrade pip -c $(LOCK) $(QUIET)
	@$(PIP) install -q -r requirements.txt -c $(LOCK) $(QUIET)
	@echo "setup 3/5: fourws itself (editable, from this checkout)"
	@$(PIP) install -q --no-deps -e . >$(VENV)/fourws-install.log 2>&1 \
	  || { cat $(VENV)/fourws-install.log; exit 1; }
	@touch $(STAMP)

# The message interfaces (the ament_cmake package of CMakeLists.txt, interfaces only, and the
# vendored interface packages of interfaces/ that no ROS wheel provides: interfaces/SOURCE.md)
# built against the ROS wheels and installed into the venv prefix, so the generated messages
# import with no extra environment. Rebuilt when a .msg or the package files change (or after
# the venv was reinstalled).
$(MSGS_STAMP): $(STAMP) $(wildcard msg/*.msg) CMakeLists.txt package.xml cmake/drop_missing_wheel_includes.cmake \
  $(wildcard interfaces/*/msg/*.msg interfaces/*/CMakeLists.txt interfaces/*/package.xml)
	@echo "setup 4/5: message interfaces (CMake against the ROS wheels, about 1 min; log $(MSGS_BUILD)/build.log)"
	@rm -rf $(MSGS_BUILD) && mkdir -p $(MSGS_BUILD)
	@V=$(abspath $(VENV)); for src in $(VENDORED_INTERFACES) .; do \
	  b=$(MSGS_BUILD)/$$(basename $$(realpath $$src)); \
	  PATH=$$V/bin:$$PATH CMAKE_PREFIX_PATH=$$V AMENT_PREFIX_PATH=$$V \
	  cmake -S $$src -B $$b -DCMAKE_INSTALL_PREFIX=$$V -DFOURWS_INTERFACES_ONLY=ON \
	  -DPython3_EXECUTABLE=$$V/bin/python -DBUILD_TESTING=OFF >>$(MSGS_BUILD)/build.log 2>&1 \
	  && PATH=$$V/bin:$$PATH cmake --build $$b -j2 >>$(MSGS_BUILD)/build.log 2>&1 \
	  && cmake --install $$b >>$(MSGS_BUILD)/build.log 2>&1 \
	  || { tail -30 $(MSGS_BUILD)/build.log; echo "message interface build of $$src failed, log: $(MSGS_BUILD)/build.log"; exit 1; }; \
	  done
	@cd /tmp && $(abspath $(PY)) -c "from fourws.msg import VehicleState; from tf2_msgs.msg import TFMessage; from ackermann_msgs.msg import AckermannDriveStamped" \
	  || { echo "the built messages do not import (fourws.msg, tf2_msgs.msg, ackermann_msgs.msg)"; exit 1; }
	@touch $(MSGS_STAMP)

# The simulator's numba kernels compiled into their disk cache (fourws_sim/warmup.py), so no
# run compiles them: again only when a kernel source changed (numba checks the cache itself).
$(KERNELS_STAMP): $(MSGS_STAMP) $(wildcard fourws_sim/*.py fourws_sim/models/*.py fourws_sim/tires/*.py)
	@echo "setup 5/5: compiling the simulator's kernels into numba's cache (minutes the first time)"
	@$(PY) -m fourws_sim.warmup
	@touch $(KERNELS_STAMP)
	@echo "setup done: $(VENV)/bin/fourws --help"

test: setup
	$(PY) -m pytest -q test

demo: setup
	$(VENV)/bin/fourws demo

bench: setup
	$(VENV)/bin/fourws bench --json

# Refresh $(LOCK): a clean install of requirements.txt (no constraints) into a new venv, frozen.
# Commit the result once `make test` passes with it.
lock:
	@echo "lock: clean install of requirements.txt into $(LOCK_VENV)"
	@rm -rf $(LOCK_VENV) && python3 -m venv $(LOCK_VENV)
	@$(LOCK_VENV)/bin/pip install -q --upgrade pip $(QUIET)
	@$(LOCK_VENV)/bin/pip install -q -r requirements.txt $(QUIET)
	@{ echo "# Versions installed by \`make setup\` (pip constraints). Produced by \`make lock\` from a"; \
	  echo "# clean install of requirements.txt with $$($(LOCK_VENV)/bin/python -V); do not edit."; \
	  $(LOCK_VENV)/bin/pip freeze --all; } > $(LOCK)
	@rm -rf $(LOCK_VENV)
	@echo "lock: wrote $(LOCK) ($$(grep -c "==" $(LOCK)) pins); run make setup test"

clean:
	rm -rf build install log runs report
