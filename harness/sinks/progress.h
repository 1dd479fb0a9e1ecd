// The progress lines of a run, on stderr: what is to do, a line as each combination
// begins (elapsed time and an estimate of what is left from the combinations measured so
// far), a line for each that did not end ok, and the summary (rows written by status,
// the models that did not load).
#pragma once

#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "run/run_sink.h"

namespace accelbench {

class Progress : public RunSink {
public:
    explicit Progress(std::FILE* out = stderr) : out_(out) {}
    void context(const RunContext& context) override;
    void starting(const Combination& c) override;
    void report(const CombinationResult& result) override;
    void finalize() override;

private:
    using Clock = std::chrono::steady_clock;
    double elapsed_s() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

    std::FILE* out_;
    std::string config_name_, out_path_;
    Clock::time_point start_;
    size_t to_do_ = 0, begun_ = 0, not_written_ = 0, measured_ = 0;
    double measured_s_ = 0;
    std::map<std::string, size_t> by_status_;
    std::vector<std::string> unloadable_;  // "label: why" of models that did not load
};

}  // namespace accelbench
