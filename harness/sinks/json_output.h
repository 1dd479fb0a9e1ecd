// Google Benchmark's JSON for the whole run (--benchmark_out=FILE, for GB's compare.py),
// assembled from each combination's run objects: they are measured in child processes,
// which must not write the file.
#pragma once

#include <benchmark/benchmark.h>

#include <fstream>

#include "run/run_sink.h"

namespace accelbench {

class JsonOutput : public RunSink {
public:
    // Opens the file and writes GB's context (the run's start); throws when it cannot be opened.
    explicit JsonOutput(const std::string& path);
    ~JsonOutput() override { finalize(); }
    void report(const CombinationResult& result) override;
    void finalize() override;

private:
    std::ofstream file_;
    std::string path_;
    benchmark::JSONReporter reporter_;
    bool first_ = true, finalized_ = false;
};

}  // namespace accelbench
