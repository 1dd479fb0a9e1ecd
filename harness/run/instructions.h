// Instruction counts of one measured render under callgrind (tier 2 of `make regress`:
// a count that, unlike time, does not depend on the machine's load).
//
// Run as
//   valgrind --tool=callgrind --instr-atstart=no --callgrind-out-file=OUT
//       accelbench run --in-process --instructions OUT CONFIG.yaml
// The harness then switches callgrind's instrumentation on around the first counted
// render repetition of each combination only (client requests from valgrind's
// callgrind.h), dumps the counts with the combination's id as the dump's description,
// reads the dump back (OUT.<part>) and writes its Ir total into the `instructions` column.
// Outside valgrind the client requests are a few no-op instructions and nothing is read:
// a normal run leaves the column empty and pays nothing.
#pragma once

#include <cstdint>
#include <string>

namespace accelbench {

// True when this process runs under valgrind (any tool).
bool running_on_valgrind();

// Brackets exactly one region: start() zeroes callgrind's counters and switches
// instrumentation on; stop() switches it off and dumps with a description unique to
// this process and `tag`, then returns the dump's Ir total read from the dump file.
// Throws std::runtime_error when the dump cannot be found or parsed (e.g. valgrind's
// --callgrind-out-file differs from `out_file`, or the tool is not callgrind).
class CallgrindRegion {
public:
    CallgrindRegion(std::string out_file, std::string tag);
    void start();
    uint64_t stop();

private:
    std::string out_file_, description_;
};

// The Ir total of the dump in `out_file`.<part> whose trigger description is `description`:
// its `totals:` line (`summary:` when there is none). Throws std::runtime_error when no
// such dump exists or it has no total.
uint64_t read_callgrind_dump(const std::string& out_file, const std::string& description);

}  // namespace accelbench
