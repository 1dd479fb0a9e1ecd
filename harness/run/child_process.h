// A child process that a time limit can stop: `accelbench run` measures each combination
// and prepares each model in one (unless --in-process), so a crash, a hang or an
// exhausted memory ends one combination, not the run. What the child sends back crosses
// the pipe in the wire form (util/wire.h), as frames: each stage it begins, then its result.
#pragma once

#include <functional>
#include <optional>
#include <string>

namespace accelbench {

// Told each stage a piece of work begins: the name a timeout or crash message gives.
using StageFn = std::function<void(const std::string&)>;

// What a forked child gave back (run_in_child): its result, or why there is none.
struct ChildOutcome {
    std::optional<std::string> result;  // the work's return value, when it finished in time
    bool timed_out = false;             // killed at the deadline
    std::string failure;                // no result otherwise: "died from signal 11 (...)", "exited with status 3 ..."
    std::string stage;                  // the last stage the child began
};

// Runs `work` in a forked child with the deadline `timeout_s` and brings its return value
// (any bytes: the caller's wire form) back through a pipe; the child reports each stage it
// begins, `first_stage` until it reports one. `work` must not throw. The parent must not
// have started threads (fork copies one thread). A child stopped by SIGTERM, SIGINT,
// SIGHUP or SIGQUIT stops this process with the same signal (the whole run is being
// stopped); a crash (any other signal) or an exit without a result is `failure`.
ChildOutcome run_in_child(const std::function<std::string(const StageFn&)>& work, double timeout_s,
                          const std::string& first_stage = "start-up");

// "exceeded the time limit (timeout_s = 2 s) during <stage>"; for a child that times
// several combinations (a deadline of timeout_s each), "(timeout_s = 2 s for each of the 4
// combinations timed in one process)".
std::string time_limit_message(double timeout_s, const std::string& stage, size_t combinations = 1);

}  // namespace accelbench
