// The repetitions CSV (<results>.reps.csv): one row per counted repetition of a
// combination measured ok, its build and render time. Written before the combination's
// results row, so a run killed in between leaves repetitions that --resume drops
// (prepare_resume), never a results row without its samples.
#pragma once

#include "csv/results.h"
#include "run/run_sink.h"

namespace accelbench {

class RepetitionsCsv : public RunSink {
public:
    explicit RepetitionsCsv(const std::string& path) : file_(path, repetition_columns()) {}
    void context(const RunContext& context) override { config_name_ = context.config.name; }
    void report(const CombinationResult& result) override;

private:
    CsvAppender file_;
    std::string config_name_;
};

}  // namespace accelbench
