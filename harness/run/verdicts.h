// Robustness cases in a benchmark run: a combination whose model is a case of the
// extreme-case catalogue is judged against the case's requirements instead of timed;
// `accelbench run` ends with a table of every case's verdict per accelerator
// (sinks/verdict_table.h).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "accelbench/verify/robustness_cases.h"
#include "plan/combinations.h"
#include "run/measure.h"

namespace accelbench {

// Judges `c` with the accelerator (judge_case: two builds, every ray traced closest-hit
// and any-hit, compared with the case's expectations and the reference). The result is
// status ok with the columns verdict (pass/fail), verdict_counts, the error columns
// against the reference and peak_rss_bytes; the failure detail is the message. Build
// and depth statistics go to the tree_depth and memory_bytes columns. Errors a harness
// must report (an invalid parameter) throw.
// `given` are the parameters as the config gives them (the rest take their defaults,
// resolved for the case's scene).
Measurement judge_measurement(const std::string& accel, const std::map<std::string, std::string>& given,
                              const RobustnessCase& c, const StageFn& stage = {});

}  // namespace accelbench
