// The verdicts of a run's robustness cases: a combination whose model is a case of the
// extreme-case catalogue is judged against the case's requirements instead of timed
// (verdicts.h), and `accelbench run` ends with this table: cases as rows, accelerator
// settings as numbered columns (their legend above the table), then every failure with
// its counts and detail. Printed at the end only when the run judged a case.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "run/run_sink.h"

namespace accelbench {

class VerdictTable : public RunSink {
public:
    explicit VerdictTable(std::FILE* out = stdout) : out_(out) {}
    void report(const CombinationResult& result) override;
    void finalize() override;

    // One combination's outcome: its verdict when judged, else its status (a timeout or a
    // crash of a case is a failure of its own kind).
    void add(const std::string& case_label, const Combination& c, const Measurement& m);
    bool empty() const { return cells_.empty(); }
    void print(std::FILE* out) const;

private:
    struct Cell {
        size_t row, column;
        std::string text;     // pass, FAIL, t/o, err, skip
        std::string details;  // failures only
    };
    std::FILE* out_;
    std::vector<std::string> rows_, columns_;
    std::vector<Cell> cells_;
};

}  // namespace accelbench
