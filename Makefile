# impactchain: `make run` and `make test` set everything up on a fresh Debian machine.
SHELL := /bin/bash
.ONESHELL:
.SHELLFLAGS := -eu -o pipefail -c

VENV := .venv
PY := $(VENV)/bin/python
FPM := $(abspath $(VENV))/bin/fpm
RELEASE := --profile release
# gfortran's runtime checks: bounds, and traps on invalid operations, division by zero, overflow
CHECKED := --flag "-g -O1 -fcheck=all -ffpe-trap=invalid,zero,overflow -fbacktrace"
APT_PACKAGES := gfortran libhdf5-dev liblapack-dev libblas-dev pkg-config \
                libopenmpi-dev openmpi-bin
PY_STAMP := $(VENV)/.requirements-installed
DEFAULT_RUN := runs/default.h5

.PHONY: all setup system-deps python-deps build run test fortran-test python-test \
        figures bench clean help

all: build

help:
	@echo "make run      set up, build, run namelists/default.nml, draw its figures"
	@echo "make test     set up, build, run fpm test and pytest"
	@echo "make figures  regenerate every figure of the paper into figures/"
	@echo "make bench    build with the release profile and run the benchmark table"

setup: system-deps python-deps

# Debian packages: installed when root, otherwise the exact command is printed.
system-deps:
	@missing=""
	for p in $(APT_PACKAGES); do
	    dpkg -s "$$p" >/dev/null 2>&1 || missing="$$missing $$p"
	done
	if [ -z "$$missing" ]; then exit 0; fi
	if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
	    echo "impactchain: installing Debian packages:$$missing"
	    export DEBIAN_FRONTEND=noninteractive
	    apt-get update -qq
	    apt-get install -y -qq --no-install-recommends $$missing >/dev/null
	else
	    echo "impactchain: missing system packages:$$missing"
	    echo "run as root:  apt-get update && apt-get install -y$$missing"
	    echo "(elsewhere: a Fortran 2008 compiler, HDF5 with Fortran bindings, LAPACK, pkg-config)"
	    exit 1
	fi

python-deps: $(PY_STAMP)

$(PY_STAMP): requirements.txt
	@if [ ! -x $(PY) ]; then python3 -m venv $(VENV); fi
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.txt
	touch $@

build: setup
	$(FPM) build $(RELEASE)
	$(PY) f2py/build.py

run: build
	@mkdir -p runs
	$(FPM) run $(RELEASE) -- namelists/default.nml
	$(PY) -m post all $(DEFAULT_RUN) -o runs/default
	@echo "impactchain: figures written next to $(DEFAULT_RUN) (runs/default_*.png)"

fortran-test: build
	$(FPM) test $(RELEASE)
	@echo "impactchain: the same tests with runtime checks"
	$(FPM) test $(CHECKED)

python-test: build
	IMPACTCHAIN_REQUIRE_EXTENSION=1 $(PY) -m pytest
	@echo "impactchain: the simulator tests again against the runtime-checked build"
	IMPACTCHAIN_FPM_FLAGS='-g -O1 -fcheck=all -ffpe-trap=invalid,zero,overflow -fbacktrace' \
	    $(PY) -m pytest -q test/python

test: fortran-test python-test

bench: build
	$(PY) bench/run_bench.py --fpm $(FPM)

clean:
	rm -rf build runs/*.h5 runs/*.png post/_kernels*
