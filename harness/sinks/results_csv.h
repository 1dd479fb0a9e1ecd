// The results CSV: one row per combination (results.h lists the columns; docs/configs.md
// says what they hold), written and flushed as each combination finishes.
#pragma once

#include <optional>

#include <string>
#include <vector>

#include "csv/provenance.h"
#include "csv/results.h"
#include "run/run_sink.h"

namespace accelbench {

// The results row of a combination: identification, parameters, render settings and
// provenance, then the measurement's status and, when ok, its statistics and counts.
// `embree_isa`: the run's shared Embree kernels (embree_isa_of_rows), if any.
Row result_row(const Config& config, const CombinationResult& result,
               const std::optional<std::string>& embree_isa = std::nullopt);

// The max_isa of every Embree combination of `config`.
std::vector<std::string> embree_max_isas(const Config& config);

class ResultsCsv : public RunSink {
public:
    // Opens (or continues) the file; throws when its header differs from this build's.
    explicit ResultsCsv(const std::string& path) : file_(path, result_columns()) {}
    void context(const RunContext& context) override {
        config_ = &context.config;
        embree_isa_ = embree_isa_of_rows(embree_max_isas(context.config));
    }
    void report(const CombinationResult& result) override {
        if (result.written()) file_.append(result_row(*config_, result, embree_isa_));
    }

private:
    CsvAppender file_;
    const Config* config_ = nullptr;
    std::optional<std::string> embree_isa_;
};

}  // namespace accelbench
