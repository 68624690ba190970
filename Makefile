# impactchain: `make run` and `make test` set everything up on a fresh Debian machine.
SHELL := /bin/bash
.ONESHELL:
.SHELLFLAGS := -eu -o pipefail -c

VENV := .venv
PY := $(VENV)/bin/python
FPM := $(abspath $(VENV))/bin/fpm
RELEASE := --profile release
# gfortran's runtime checks: bounds, and traps on invalid operations, division by zero, overflow
# (and a warning for each array temporary: none is expected, so one stands out in the log)
CHECKED_FLAGS = -g -O1 -fcheck=all -ffpe-trap=invalid,zero,overflow -fbacktrace $(BLAS_FFLAGS)
CHECKED = --flag "$(CHECKED_FLAGS)"
# Which BLAS and LAPACK (docs/performance.md, "Which BLAS"): the pkg-config module(s) named by
# IMPACTCHAIN_BLAS, default scipy-openblas: the scipy-openblas32 wheel of requirements.txt,
# the OpenBLAS numpy and scipy build against (kernels for new CPUs, symbols prefixed scipy_),
# whose pkg-config file inside the wheel is put on PKG_CONFIG_PATH here. Another one:
# `make IMPACTCHAIN_BLAS=openblas build` (Debian's libopenblas-dev: a threaded build, which
# src/base/chain_blas_runtime.c pins to one thread; never libopenblas0-serial, not thread-safe),
# `IMPACTCHAIN_BLAS=lapack` (Debian's liblapack-dev on the libblas.so.3 its alternatives
# select), or a cluster module's .pc. fpm gets
# the module's flags through FPM_LDFLAGS and FPM_CFLAGS (its Cflags name a symbol prefix, for
# src/base/chain_blas_names.c), meson.build reads IMPACTCHAIN_BLAS itself.
# `eval "$$(make -s blas-env)"` sets the same for fpm and pytest run by hand.
IMPACTCHAIN_BLAS ?= scipy-openblas
export IMPACTCHAIN_BLAS
# (looked up by the shell each time, not by make's $(wildcard), which caches a directory's
# contents and on a fresh clone would never see the .venv that `setup` creates)
SCIPY_OPENBLAS_PC = $(shell ls -d \
    $(abspath $(VENV))/lib/python3*/site-packages/scipy_openblas32/lib/pkgconfig 2>/dev/null \
    | head -n 1)
PKG_CONFIG_PATH_0 := $(PKG_CONFIG_PATH)
export PKG_CONFIG_PATH = $(subst $(eval) ,:,$(strip $(SCIPY_OPENBLAS_PC) \
                                                    $(subst :, ,$(PKG_CONFIG_PATH_0))))
BLAS_PKG_CONFIG = PKG_CONFIG_PATH="$(PKG_CONFIG_PATH)" pkg-config
# (fpm puts FPM_LDFLAGS before the objects, and gcc may link --as-needed, which would drop a
# library named before anything needs it: --no-as-needed for the BLAS alone)
export FPM_LDFLAGS = -Wl,--push-state,--no-as-needed \
    $(shell $(BLAS_PKG_CONFIG) --libs $(IMPACTCHAIN_BLAS) 2>/dev/null) -Wl,--pop-state
export FPM_CFLAGS = $(shell $(BLAS_PKG_CONFIG) --cflags $(IMPACTCHAIN_BLAS) 2>/dev/null)
# fpm keeps one build directory per set of Fortran flags, but neither recompiles the C files
# when FPM_CFLAGS changes nor relinks when FPM_LDFLAGS does: the Fortran flags carry the
# symbol prefix and a digest of the BLAS's flags (defines, which no Fortran file uses), so
# that builds for different BLAS never share objects or executables. --flag replaces
# FPM_FFLAGS, so the runtime-checked flags carry them too.
BLAS_FFLAGS = $(filter -D%,$(FPM_CFLAGS)) \
    -DIMPACTCHAIN_BLAS_FLAGS=$(shell echo '$(FPM_LDFLAGS) $(FPM_CFLAGS)' | md5sum | cut -c1-12)
# Code generation for this machine's CPU, opt-in (docs/performance.md, "Flags for the
# machine"): e.g. `make MACHINE_FLAGS=-march=native build`. The same flags reach fpm (its
# Fortran flags, so the build gets a directory of its own) and the Python extension
# (meson.build reads IMPACTCHAIN_MACHINE_FLAGS), which keeps the two bit-identical on this
# machine; the extension is built in a directory of its own per set of flags, as meson reads
# them only when it configures one. Not for the runtime-checked build, which tests the code
# rather than its code generation.
MACHINE_FLAGS ?=
export IMPACTCHAIN_MACHINE_FLAGS = $(strip $(MACHINE_FLAGS))
export FPM_FFLAGS = $(strip $(BLAS_FFLAGS) $(IMPACTCHAIN_MACHINE_FLAGS))
APT_PACKAGES := gfortran libhdf5-dev liblapack-dev libblas-dev pkg-config libopenmpi-dev \
                openmpi-bin
PY_STAMP := $(VENV)/.requirements-installed
# The Python package impactchain (python/impactchain/ and its extension impactchain._kernels,
# built by meson-python from meson.build): installed into the venv as `pip install .` installs
# it anywhere, from a build directory kept between runs, so that a rebuild compiles only what
# changed (nothing changed: a few seconds). meson and ninja come from the venv.
PKG_BUILD := $(CURDIR)/build/meson-python$(if $(IMPACTCHAIN_MACHINE_FLAGS),-$(shell \
    echo '$(IMPACTCHAIN_MACHINE_FLAGS)' | md5sum | cut -c1-8))
INSTALL_PKG := PATH="$(abspath $(VENV))/bin:$$PATH" $(PY) -m pip install --quiet \
               --no-build-isolation --no-deps -Cbuild-dir=$(PKG_BUILD) .
DEFAULT_RUN := runs/default.h5
# fpm prints a line as it starts and one as it ends each file it compiles (hundreds on a fresh
# build): left out of the log, keeping the compiler's messages, fpm's errors and its summary
# line. (fpm writes them to stderr; sed keeps every other line, in order, and exits 0, so
# that pipefail reports fpm's status.)
FPM_LOG := 2>&1 | sed -u -E '/^\[ *[0-9]+%\] +[^ ]+( +done\.)?$$/d'

.PHONY: all setup system-deps python-deps blas-check blas-env build run test fortran-test \
        python-test mpi figures bench recipe-reference api-docs docs docs-deps docs-test clean help

all: build

help:
	@echo "make run      set up, build, run namelists/default.nml, draw its figures"
	@echo "make test     set up, build, run fpm test and pytest"
	@echo "make figures  regenerate every figure of the paper into figures/"
	@echo "make census-figures  only the attractor censuses' figures (minutes)"
	@echo "make bench    build with the release profile, run the benchmark table and the numba reference"
	@echo "make recipe-reference  rewrite test/recipes/reference.json (results meant to change)"
	@echo "make api-docs the API reference (Fortran and Python) into docs/api/"
	@echo "make docs     the documentation site into site/ (tutorials executed, references generated)"

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

# the BLAS of IMPACTCHAIN_BLAS must be there before anything is compiled
blas-check: setup
	@$(BLAS_PKG_CONFIG) --exists $(IMPACTCHAIN_BLAS) || {
	    echo "impactchain: pkg-config finds no '$(IMPACTCHAIN_BLAS)' (IMPACTCHAIN_BLAS;" \
	         "PKG_CONFIG_PATH=$(PKG_CONFIG_PATH)); README, Which BLAS" >&2; exit 1; }

# what the Makefile gives fpm and meson, as shell commands: eval "$$(make -s blas-env)"
blas-env: blas-check
	@echo "export IMPACTCHAIN_BLAS='$(IMPACTCHAIN_BLAS)'"
	echo "export PKG_CONFIG_PATH='$(PKG_CONFIG_PATH)'"
	echo "export FPM_LDFLAGS='$(FPM_LDFLAGS)'"
	echo "export FPM_CFLAGS='$(FPM_CFLAGS)'"
	echo "export FPM_FFLAGS='$(FPM_FFLAGS)'"
	echo "export IMPACTCHAIN_MACHINE_FLAGS='$(IMPACTCHAIN_MACHINE_FLAGS)'"

build: setup blas-check
	$(FPM) build $(RELEASE) $(FPM_LOG)
	$(INSTALL_PKG)

run: build
	@mkdir -p runs
	$(FPM) run $(RELEASE) -- --overwrite namelists/default.nml
	$(PY) -m impactchain all $(DEFAULT_RUN) -o runs/default
	@echo "impactchain: figures written next to $(DEFAULT_RUN) (runs/default_*.png)"

# the MPI driver of sweeps and censuses (optional for users; built and run by make test)
mpi: build
	cd mpi && $(FPM) build $(RELEASE) --compiler mpifort $(FPM_LOG)

fortran-test: build mpi
	@echo "impactchain: the Fortran tests (release build)"
	$(FPM) test $(RELEASE) $(FPM_LOG)
	@echo "impactchain: the same tests with runtime checks"
	$(FPM) test $(CHECKED) $(FPM_LOG)

# pytest-xdist spreads the tests over the machine's cores, a test file per worker at a time
# (so that a file's shared fixtures run once); PYTEST_JOBS=0 runs them in this process
PYTEST_JOBS ?= auto
PYTEST_PARALLEL := -n $(PYTEST_JOBS) --dist loadscope

python-test: build
	@echo "impactchain: the Python tests (package and simulator, release build)"
	IMPACTCHAIN_REQUIRE_EXTENSION=1 $(PY) -m pytest $(PYTEST_PARALLEL)
	@echo "impactchain: pip install of the repository into a fresh venv (a full build)"
	$(PY) -m pytest -m install -q -rA test/python/package/test_install.py
	@echo "impactchain: the simulator tests again against the runtime-checked build"
	$(FPM) build $(CHECKED) $(FPM_LOG)
	IMPACTCHAIN_FPM_FLAGS='$(CHECKED_FLAGS)' \
	    $(PY) -m pytest -q $(PYTEST_PARALLEL) test/python --ignore=test/python/package

test: fortran-test python-test docs-test

# the benchmark's own packages (numba for the reference implementation): not needed by make test
BENCH_STAMP := $(VENV)/.bench-requirements-installed

$(BENCH_STAMP): requirements-bench.txt $(PY_STAMP)
	$(PY) -m pip install --quiet -r requirements-bench.txt
	touch $@

bench: build $(BENCH_STAMP)
	$(PY) bench/run_bench.py --fpm $(FPM)
	$(PY) bench/reference_bench.py

# Every recipe's reference values, as pytest checks them within their tolerances
# (test/python/test_recipes.py). Run it only when a change is meant to alter results, and
# commit the reference with that change.
recipe-reference: build
	$(PY) test/recipes/recipe_reference.py compute --jobs $$(nproc)

# The documentation site (docs/README.md): MkDocs with the Material theme into site/, from the
# pages of docs/, the tutorial notebooks of docs/tutorials/ (executed as the site is built:
# a failing cell fails the build), the input and output references generated from
# `impactchain --schema`, and the API references of `make api-docs`. Its Python packages come
# from requirements-docs.txt; its tests open every page in Debian's headless Chromium.
DOCS_STAMP := $(VENV)/.docs-requirements-installed
DOCS_APT_PACKAGES := chromium chromium-driver
VENV_PATH := PATH="$(abspath $(VENV))/bin:$$PATH"

docs-deps: $(DOCS_STAMP)
	@$(MAKE) --no-print-directory system-deps APT_PACKAGES="$(DOCS_APT_PACKAGES)"

$(DOCS_STAMP): requirements-docs.txt $(PY_STAMP)
	$(PY) -m pip install --quiet -r requirements-docs.txt
	touch $@

# The API reference, generated from the documentation comments: FORD for the Fortran
# library (docs/ford.md), pdoc for the Python package; into docs/api/ (not kept in git).
api-docs: build docs-deps
	rm -rf docs/api
	$(VENV)/bin/ford --quiet docs/ford.md
	PDOC_ALLOW_EXEC=1 $(VENV)/bin/pdoc impactchain -o docs/api/python
	@echo "impactchain: API reference in docs/api/fortran/index.html and docs/api/python/index.html"

docs: api-docs
	@start=$$(date +%s)
	$(VENV_PATH) NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --quiet --clean
	echo "impactchain: the site is in site/index.html ($$(( $$(date +%s) - start )) s)"

# the site as a reader sees it: every page in headless Chromium, every link, every command
docs-test: docs
	$(VENV_PATH) $(PY) -m pytest -q $(PYTEST_PARALLEL) test/docs

clean:
	rm -rf build runs/*.h5 runs/*.png site

# ---- every figure of the paper: `make figures` (runs in parallel on the machine's cores) ----
RUNS := figures/runs
SIM := $(FPM) run $(RELEASE) -- --quiet --overwrite
POST := $(PY) -m impactchain
# 150 dpi PNG; every figure carries the code version, inputs and sources in its metadata
GALLERY := --dpi 150
# One y range for the figures compared side by side (1a-1d, 2a-2f, the two of 12); a value
# outside it is counted in the figure's title.
FIG1_Y := --ylim=-3.0,1.1
FIG2_Y := --ylim=-2.3,1.2
FIG12_Y := --ylim=0,11
SINGLE := fig1a fig1b fig1c fig1d fig2a fig2b fig2c fig2d fig2e fig2f fig3_red fig3_green \
          fig4_7 fig1c_clv
SWEEPS := fig10 fig11_b005 fig11_b010 fig11_b015 fig12_K08 fig12_K06 fig12_K04 fig13
FIGURES := $(foreach f,fig1a fig1b fig1c fig1d fig2a fig2b fig2c fig2d fig2e fig2f,figures/$(f).png) \
           figures/fig3.png figures/fig4.png figures/fig5.png figures/fig6.png \
           figures/fig7.png figures/fig8.png figures/fig10.png figures/fig11.png \
           figures/fig12_damping.png figures/fig12_restitution.png figures/fig13.png \
           figures/fig10_branches.png figures/fig1c_clv_space_time.png \
           figures/fig1c_clv_ipr.png figures/fig1c_clv_angles.png $(CENSUS_FIGURES) \
           $(CHART_FIGURES)
# Attractor censuses at the paper's disputed figures (README, Basin fractions): their inputs
# live in gallery/census/, not namelists/, because test/python/test_recipes.py reruns every
# recipe in namelists/ in CI and these take minutes (about 750 CPU seconds, all six).
CENSUS := gallery/census
CENSUS_FIGURES := $(foreach f,fig1a fig1b fig1d fig2 fig3,figures/census_$(f).png) \
                  figures/census_fig3_plane.png
# Two-parameter charts (docs/gallery.md, Figure 10's chain and the default chain in (A, w)):
# their inputs live in gallery/charts/ for the same reason (the maps' sweeps take about 35
# and 15 CPU seconds).
CHARTS := gallery/charts
CHART_FIGURES := figures/chart_fig10.png figures/chart_default.png
CHART_FIG10_CURVES := $(foreach f,grazing_down grazing_up fold_down fold_up,\
                        $(RUNS)/chart_fig10_$(f).h5)
CHART_DEFAULT_CURVES := $(foreach f,grazing_down grazing_up fold_down fold_up,\
                          $(RUNS)/chart_default_$(f).h5)

.PHONY: figures figure-files census-figures
.SECONDARY:
figures: build
	@mkdir -p $(RUNS)
	@start=$$(date +%s)
	$(MAKE) --no-print-directory -j $$(nproc) figure-files
	echo "impactchain: every figure of the paper is in figures/ ($$(( $$(date +%s) - start )) s)"

figure-files: $(FIGURES)

# only the censuses' figures (a part of `make figures`)
census-figures: build
	@mkdir -p $(RUNS)
	$(MAKE) --no-print-directory figure-files FIGURES="$(CENSUS_FIGURES)"

$(RUNS)/%.h5: namelists/%.nml
	@mkdir -p $(@D)
	echo "impactchain: running $<"
	$(SIM) $<

$(RUNS)/census_%.h5: $(CENSUS)/census_%.nml
	@mkdir -p $(@D)
	echo "impactchain: running $<"
	$(SIM) $<

$(RUNS)/chart_%.h5: $(CHARTS)/chart_%.nml
	@mkdir -p $(@D)
	echo "impactchain: running $<"
	$(SIM) $<

figures/chart_fig10.png: $(CHART_FIG10_CURVES) $(RUNS)/chart_fig10_map.h5
	$(POST) chart $(CHART_FIG10_CURVES) --over $(RUNS)/chart_fig10_map.h5 -o $@ $(GALLERY)
figures/chart_default.png: $(CHART_DEFAULT_CURVES) $(RUNS)/chart_default_map.h5
	$(POST) chart $(CHART_DEFAULT_CURVES) --over $(RUNS)/chart_default_map.h5 \
	    --quantity exponent -o $@ $(GALLERY)

figures/census_fig3_plane.png: $(RUNS)/census_fig3_plane.h5
	$(POST) basin-plane $< -o $@ $(GALLERY)
figures/census_%.png: $(RUNS)/census_%.h5
	$(POST) basin-fractions $< -o $@ $(GALLERY)

# the covariant vectors of figure 1c's chain (before the pattern rule of figures 1a-1d)
figures/fig1c_clv_space_time.png: $(RUNS)/fig1c_clv.h5
	$(POST) clv-space-time $< --vector 1,2 --start 2230 --cycles 120 -o $@ $(GALLERY)
figures/fig1c_clv_ipr.png: $(RUNS)/fig1c_clv.h5
	$(POST) clv-ipr $< -o $@ $(GALLERY)
figures/fig1c_clv_angles.png: $(RUNS)/fig1c_clv.h5
	$(POST) clv-angles $< -o $@ $(GALLERY)
figures/fig1%.png: $(RUNS)/fig1%.h5
	$(POST) space-amplitude $< -o $@ $(FIG1_Y) $(GALLERY)
figures/fig2%.png: $(RUNS)/fig2%.h5
	$(POST) space-amplitude $< -o $@ $(FIG2_Y) $(GALLERY)
figures/fig3.png: $(RUNS)/fig3_red.h5 $(RUNS)/fig3_green.h5
	$(POST) space-amplitude $^ -o $@ $(GALLERY)
figures/fig4.png: $(RUNS)/fig4_7.h5
	$(POST) space-time-amplitude $< --panel-cycles 60 --panels 4 -o $@ $(GALLERY)
figures/fig5.png: $(RUNS)/fig4_7.h5
	$(POST) space-time-amplitude $< --panel-cycles 60 --panels 4 --start 741 -o $@ $(GALLERY)
figures/fig6.png: $(RUNS)/fig4_7.h5
	$(POST) shock-wave $< --panel-cycles 60 --panels 4 -o $@ $(GALLERY)
figures/fig7.png: $(RUNS)/fig4_7.h5
	$(POST) shock-wave $< --panel-cycles 60 --panels 4 --start 741 -o $@ $(GALLERY)
figures/fig8.png: $(RUNS)/fig4_7.h5
	$(POST) poincare $< --site 1 --cycles 50 -o $@ $(GALLERY)
figures/fig10.png: $(RUNS)/fig10.h5
	$(POST) bifurcation $< -o $@ $(GALLERY)
figures/fig10_branches.png: $(RUNS)/fig10_branches.h5 $(RUNS)/fig10_fold.h5 \
                            $(RUNS)/fig10_free.h5 $(RUNS)/fig10.h5
	$(POST) branches $(RUNS)/fig10_branches.h5 $(RUNS)/fig10_fold.h5 $(RUNS)/fig10_free.h5 \
		--over $(RUNS)/fig10.h5 -o $@ $(GALLERY)
figures/fig11.png: $(RUNS)/fig11_b005.h5 $(RUNS)/fig11_b010.h5 $(RUNS)/fig11_b015.h5
	$(POST) lyapunov $^ --k 10 --with-bifurcation -o $@ $(GALLERY)
figures/fig12_damping.png: $(RUNS)/fig11_b005.h5 $(RUNS)/fig11_b010.h5 $(RUNS)/fig11_b015.h5
	$(POST) ky-dimension $^ -o $@ $(FIG12_Y) $(GALLERY)
figures/fig12_restitution.png: $(RUNS)/fig12_K08.h5 $(RUNS)/fig12_K06.h5 $(RUNS)/fig12_K04.h5
	$(POST) ky-dimension $^ -o $@ $(FIG12_Y) $(GALLERY)
figures/fig13.png: $(RUNS)/fig13.h5
	$(POST) lyapunov $< --k 32 -o $@ $(GALLERY)
