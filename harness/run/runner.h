// Running a plan: for each combination still to do, in the plan's order grouped by model,
// result = measure it (or skip it by a rule), then hand the result to every sink —
// Google Benchmark's runner/reporter split (STYLE.md "Runner and reporters").
#pragma once

#include <vector>

#include "plan/run_plan.h"
#include "run/run_sink.h"

namespace accelbench {

// Each model is loaded at most once, when something is measured on it or its triangle
// count is needed for a skip rule; with `errors`, the reference's answers are traced once
// per model before its first measurement. A measurement runs in a child process
// (run_isolated) unless --in-process. Returns the exit code: 2 when a model did not load
// (its combinations get no rows) or an output could not be written (the run stops at
// once), 1 when a combination ended in error, else 0.
int run_plan(const RunPlan& plan, const RunOptions& options, const std::vector<RunSink*>& sinks);

}  // namespace accelbench
