// The results CSV: one row per combination (results.h lists the columns; docs/configs.md
// says what they hold), written and flushed as each combination finishes.
#pragma once

#include <optional>

#include "csv/results.h"
#include "run/run_sink.h"

namespace accelbench {

// The results row of a combination: identification, parameters, render settings and
// provenance, then the measurement's status and, when ok, its statistics and counts.
Row result_row(const Config& config, const CombinationResult& result);

class ResultsCsv : public RunSink {
public:
    // Opens (or continues) the file; throws when its header differs from this build's.
    explicit ResultsCsv(const std::string& path) : file_(path, result_columns()) {}
    void context(const RunContext& context) override { config_ = &context.config; }
    void report(const CombinationResult& result) override {
        if (result.written()) file_.append(result_row(*config_, result));
    }

private:
    CsvAppender file_;
    const Config* config_ = nullptr;
};

}  // namespace accelbench
