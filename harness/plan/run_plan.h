// Planning `accelbench run`: config -> combinations -> this shard's -> the output file ->
// what is still to do (--resume). Nothing is measured here (runner.h measures).
#pragma once

#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "config/config.h"
#include "csv/run_inputs.h"
#include "models/model_registry.h"
#include "plan/combinations.h"
#include "util/output_lock.h"

namespace accelbench {

// `accelbench run`'s options (run_command.cpp parses them).
struct RunOptions {
    std::string config_path;
    bool dry_run = false, dry_run_json = false, resume = false, in_process = false, show_repetitions = false;
    bool allow_mixed = false;  // --resume may append to rows of another build (check_same_build)
    std::string out, json_out, callgrind_out;
    std::optional<Shard> shard;
    std::vector<std::string> benchmark_args;
};

// A command line that cannot be followed: printed with the usage, exit 2.
struct UsageError : std::invalid_argument {
    using std::invalid_argument::invalid_argument;
};

struct RunPlan {
    ModelRegistry registry;
    Config config;
    std::vector<Combination> all;              // the config's, in expansion order
    std::optional<Shard> shard;                // --shard, else SLURM's array task
    std::vector<const Combination*> selected;  // this shard's
    RunInputs inputs;                          // what the rows are measured from (inputs_of)
    std::string out;                           // the results CSV (its repetitions beside it)
    std::set<std::string> done;                // combo_ids already in `out` (--resume)
    std::vector<const Combination*> to_do;     // selected minus done
    OutputLock lock;                           // `out` and its repetitions, for the whole run
};

// The inputs a config's rows are measured from, besides the code: the config file's
// sha256 (named by the config's name), each model's (a mesh file's, or for a registry
// model its entry's: the file's checksum, camera and light; procedural scenes and
// robustness cases are made by the code) and each ray file's. Throws std::runtime_error
// for a file that cannot be read.
RunInputs inputs_of(const Config& config, const ModelRegistry& registry);

// Why a model given by path cannot be measured as the run recorded it: its file's sha256
// is no longer the one in plan.inputs (it was replaced while the run went on); "" when it
// is, and for every other kind of model (the registry checks its own files).
std::string model_file_changed(const RunPlan& plan, const ModelSpec& model);

// The config (ConfigError lists its issues), its combinations, this shard's and the inputs. Throws
// UsageError for a malformed SLURM shard, std::runtime_error for the model registry.
RunPlan plan_run(const RunOptions& options);

// --dry-run: every selected combination with its id and, where the triangle count is known
// (or cheaply found), whether a skip rule matches; then the counts. --dry-run=json (`json`):
// one JSON document with the config's models, its accelerator entries with their axes
// (canonical values, ranges expanded) and every selected combination.
void print_dry_run(const RunPlan& plan, bool json = false);

// The results file: --out, else with --resume the newest results/runs/<name>-*.csv of
// this shard, else results/runs/<name>-<timestamp>[-shardIofN].csv. Refuses (UsageError)
// an existing non-empty file, or repetitions without their results file, without
// --resume; refuses (std::runtime_error) a path that is not a regular file and an output
// that another process is writing (OutputLock, held until the plan is destroyed). With
// --resume, refuses (std::runtime_error) a file with rows whose record of inputs is
// missing or differs from `inputs`, then prepares the file (prepare_resume: a cut last
// line removed, orphan repetitions dropped) and fills `done`; then `to_do`. Writes the
// record of `inputs` beside the results file.
void choose_output(RunPlan& plan, const RunOptions& options);

// "YYYY-mm-ddTHH:MM:SSZ"-like text of the current UTC time in strftime's `format`.
std::string utc_now(const char* format);

}  // namespace accelbench
