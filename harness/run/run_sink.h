// Where the results of `accelbench run` go, in Google Benchmark's reporter shape
// (include/benchmark/reporter.h: ReportContext once, ReportRuns per run, Finalize): the
// runner (runner.h) measures each combination into a CombinationResult, a plain value, and
// hands it to every sink. Each output — the results CSV, the repetitions CSV, Google
// Benchmark's JSON, the verdict table, the progress lines — is one sink in its own file.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "config/config.h"
#include "plan/combinations.h"
#include "run/measure.h"

namespace accelbench {

// What the run is, given to every sink once before the first combination.
struct RunContext {
    const Config& config;
    const std::string& out;  // the results CSV
    std::optional<Shard> shard;
    size_t selected = 0;      // combinations in this shard
    size_t already_done = 0;  // of them, already in `out` (--resume)
    size_t to_do = 0;         // measured (or skipped by a rule) now
};

// One combination's outcome.
struct CombinationResult {
    const Combination& combination;
    const ModelSpec& model;
    std::optional<uint64_t> triangles, vertices;  // known without loading, else from the loaded model
    std::string timestamp;                        // UTC, when the combination began
    // The model did not load: no row at all (nothing that could be taken for a result;
    // --resume runs the combination once the model is fixed). Empty when it did.
    std::string load_error;
    Measurement measurement;            // status ok, skipped, error or timeout
    std::optional<double> measuring_s;  // wall time of the measurement, when one was made

    bool written() const { return load_error.empty(); }
};

class RunSink {
public:
    virtual ~RunSink() = default;
    virtual void context(const RunContext&) {}
    // Before a combination is measured (the progress line).
    virtual void starting(const Combination&) {}
    // After it; may throw (an output that cannot be written ends the run).
    virtual void report(const CombinationResult& result) = 0;
    virtual void finalize() {}
};

}  // namespace accelbench
