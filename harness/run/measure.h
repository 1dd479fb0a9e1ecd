// Measuring one combination with Google Benchmark, optionally in a child process that a
// time limit can stop.
//
// Each combination registers two benchmarks at run time, `<name>/build` and
// `<name>/render`, with manual timing, one iteration per repetition and `repetitions`
// repetitions. Their stages, in order (measure.cpp, MeasuringStages, one function each):
// `warmup` uncounted builds (GB 1.7.1's MinWarmUpTime cannot be combined with a fixed
// iteration count); the timed builds; a counting render (CountMode::Totals: the
// deterministic counters, primitive tests and node visits), which is also the first render
// warm-up, further ones (warmup > 1) running the timed path; the timed renders
// (CountMode::Off); a second counting render after them, which is also the error trace
// against the reference. Everything deterministic is compared across every run that
// produces it — build statistics across all builds, ray and hit counts across all
// renders, traversal counters across both counting renders — and any difference fails the
// combination with a message saying which value changed.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "accelbench/accel/accelerator.h"
#include "accelbench/accel/registry.h"
#include "accelbench/render/renderer.h"
#include "accelbench/verify/error_metrics.h"
#include "plan/loaded_model.h"
#include "run/child_process.h"
#include "util/wire.h"

namespace accelbench {

struct MeasureSettings {
    int repetitions = 5;
    int warmup = 1;
    bool show_repetitions = false;  // console: every repetition, not only GB's aggregates
    bool show_context = true;       // console: GB's machine description (once per run)
    bool json = false;              // keep GB's JSON run objects in Measurement::json
    double timeout_s = 0;           // > 0: checked at every stage boundary in this process
    // A later process of a combination measured in several (Config::processes): warm-ups,
    // the first counting render (its counts are compared with the first process's) and the
    // timed repetitions; no second counting render, so no error columns.
    bool timing_only = false;
    // Non-empty: callgrind's --callgrind-out-file; the first counted render repetition is
    // counted with callgrind (instructions.h), its dump described by `callgrind_tag`.
    std::string callgrind_out, callgrind_tag;
};

struct Measurement {
    std::string status = "ok";  // ok, error or timeout
    std::string message;
    std::vector<double> build_s, render_s;  // one per counted repetition, seconds (wall)
    // The measuring process (1-based) of each counted repetition, when several processes
    // measured the combination (pool_process); empty: all in one.
    std::vector<int> process;
    // The process's CPU time of each counted render (all render threads together): with
    // render.threads > 1, wall / CPU time says how well the threads were used.
    std::vector<double> render_cpu_s;
    BuildStats build;
    uint64_t rays = 0, hits = 0, shadow_rays = 0, shadow_hits = 0;
    // Totals over primary and shadow rays; nullopt when the structure does not count its
    // traversal (AcceleratorInfo::counts_traversal: Embree), so that they are written as
    // missing, never as zero.
    std::optional<RayStats> counts;
    std::optional<uint64_t> instructions;  // callgrind's Ir of one render (MeasureSettings::callgrind_out)
    // Result columns beyond timing and counts, as CSV text by column name: the error
    // columns against the reference (error_columns), peak_rss_bytes, a robustness case's
    // verdict and verdict_counts.
    std::map<std::string, std::string> columns;
    std::string json;   // GB JSONReporter run objects, comma-separated (MeasureSettings::json)
    std::string stage;  // the last stage begun, for timeout and crash messages
};

// The named statistics of BuildStats, in CSV column order: one table for the determinism
// check, the GB counters, the pipe between processes and the CSV. Exactly one of the two
// member pointers is set.
struct BuildStatField {
    const char* name;
    std::optional<uint64_t> BuildStats::*count;
    std::optional<double> BuildStats::*real;

    std::optional<double> get(const BuildStats& s) const {
        if (count) return (s.*count) ? std::optional<double>(double(*(s.*count))) : std::nullopt;
        return s.*real;
    }
};
const std::vector<BuildStatField>& build_stat_fields();

// The error columns of a combination (false_misses ... hole_pixels) as CSV text; the
// image columns only with image errors, the t columns only when a t was compared.
std::map<std::string, std::string> error_columns(const HitErrors& hits, const std::optional<ImageErrors>& image);

// Measures in this process. When model.reference is set, the second counting render
// (after the timed part) also keeps every primary hit and, in an image run, shades; the
// error columns compare those answers with the reference's. peak_rss_bytes is the process's memory high-water mark
// over the measurement (reset at its start where Linux allows), loaded model included.
// Errors (exceptions from build or render, nondeterministic
// counters, an exceeded time limit at a stage boundary) end up in the returned status and
// message; measure() itself does not throw for them.
//
// With `ray_set`, the renders trace that ray set of the model (model.ray_sets, made by
// add_ray_sets) instead of the camera's primary and shadow rays, with its query (closest
// or any hit), and the error columns compare with the set's reference answers; the
// columns get its ray_set_hash.
Measurement measure(const std::string& name, const AcceleratorInfo& info, const ParamSet& params,
                    const LoadedModel& model, const RenderSettings& render, const MeasureSettings& settings,
                    const StageFn& stage = {}, std::optional<RaySetKind> ray_set = std::nullopt);

// One combination to measure: what measure() takes, by name.
struct MeasureJob {
    std::string name;
    const AcceleratorInfo& info;
    const ParamSet& params;
    RenderSettings render;
    MeasureSettings settings;
    std::optional<RaySetKind> ray_set;
};

// Measures several combinations of one model in this process, interleaved: every build
// round before the render rounds, round k timing the k-th repetition of each combination
// that has one, in the jobs' order in odd rounds and reversed in even ones (measure.cpp,
// register_benchmarks). Each combination's stages are measure()'s, in its own order; its
// time limit counts its own stages only; the stages it reports to `stage` are prefixed
// with "<name>: ". With more than one job, peak_rss_bytes is not written (the process holds
// every structure of the group at once). One job is exactly measure(). The results are in
// the jobs' order. The settings' show_repetitions, show_context and json are job 0's.
std::vector<Measurement> measure_jobs(const std::vector<MeasureJob>& jobs, const LoadedModel& model,
                                      const StageFn& stage = {});

// Pools `next`, the same combination measured again in another process (numbered
// `process`, 2 and up), into `into`: the repetitions appended with their process number,
// peak_rss_bytes the larger. Everything deterministic (build statistics, ray and hit counts,
// traversal counters) must be equal in both, else the result is an error naming the value;
// a failed `next` fails the whole combination, its message naming the process.
void pool_process(Measurement& into, const Measurement& next, int process);

// Runs `work` in a forked child process (run_in_child) and returns its Measurement. The
// child reports each stage it begins; if it runs longer than timeout_s it is killed and the
// result is status "timeout" naming the stage. A child that crashes (signal) or exits
// without a result gives status "error" with the signal or exit code, so one broken
// structure does not end the run. The parent must not have started threads (fork copies
// one thread).
Measurement run_isolated(const std::function<Measurement(const StageFn&)>& work, double timeout_s);

// run_isolated for work that measures `count` combinations in one child, whose deadline is
// timeout_s for each of them (count x timeout_s). When the child gives no result (it
// crashed, exited early or passed the deadline), every measurement is the same error or
// timeout naming the child's last stage, and process_failed is set.
struct IsolatedMeasurements {
    std::vector<Measurement> measurements;
    bool process_failed = false;
};
IsolatedMeasurements run_isolated_all(const std::function<std::vector<Measurement>(const StageFn&)>& work, size_t count,
                                      double timeout_s);

// The wire form (util/wire.h) a measurement crosses the pipe in, every value exact.
void put_measurement(WireWriter& w, const Measurement& m);
Measurement take_measurement(WireReader& r);

}  // namespace accelbench
