// Robustness cases in a benchmark run: a combination whose model is a case of
// the extreme-case catalogue is judged against the case's requirements instead of timed,
// and `accelbench run` ends with a table of every case's verdict per accelerator.
#pragma once

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "accelbench/verify/robustness_cases.h"
#include "combinations.h"
#include "measure.h"

namespace accelbench {

// Judges `c` with the accelerator (judge_case: two builds, every ray traced closest-hit
// and any-hit, compared with the case's expectations and the reference). The result is
// status ok with the columns verdict (pass/fail), verdict_counts, the error columns
// against the reference and peak_rss_bytes; the failure detail is the message. Build
// and depth statistics go to max_depth and memory_bytes. Errors a harness must report
// (an invalid parameter) throw.
// `given` are the parameters as the config gives them (the rest take their defaults,
// resolved for the case's scene).
Measurement judge_measurement(const std::string& accel, const std::map<std::string, std::string>& given,
                              const RobustnessCase& c, const StageFn& stage = {});

// The verdicts of a run: cases as rows, accelerator settings as numbered columns (their
// legend above the table), then every failure with its counts and detail.
class VerdictTable {
public:
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
    std::vector<std::string> rows_, columns_;
    std::vector<Cell> cells_;
};

}  // namespace accelbench
