// Reading callgrind's dumps back: the right dump by its description, its Ir total.
// (Counting itself needs valgrind; `make regress` exercises it.)
#include <gtest/gtest.h>

#include "accelbench/base/temp_dir.h"
#include "harness_test_util.h"
#include "run/instructions.h"

namespace accelbench {
namespace {

using namespace testing_util;

// The header and totals of a callgrind dump, as valgrind 3.19 writes them.
std::string dump(const std::string& trigger, const std::string& totals_line) {
    return "# callgrind format\nversion: 1\ncreator: callgrind-3.19.0\npid: 23145\ncmd:  ./t\npart: 1\n\n\n"
           "desc: I1 cache: \ndesc: D1 cache: \ndesc: LL cache: \n\ndesc: Timerange: Basic block 0 - 100002\n"
           "desc: Trigger: " +
        trigger +
        "\n\npositions: line\nevents: Ir\nsummary: 0\n\n\nfl=(1) t.c\nfn=(1) main\n"
        "16 600004\n\n" +
        totals_line + "\n";
}

TEST(InstructionsTest, ReadsTheTotalsOfTheDumpWithTheDescription) {
    TempDir dir("accelbench-instructions-test-");
    const std::string out = (dir.path() / "callgrind.out").string();
    write_file(dir.path(), "callgrind.out.1", dump("Client Request: accelbench aaaa pid 7", "totals: 600007"));
    write_file(dir.path(), "callgrind.out.2", dump("Client Request: accelbench bbbb pid 7", "totals: 1200007 5"));
    write_file(dir.path(), "callgrind.out", dump("Program termination", "totals: 0"));
    write_file(dir.path(), "other.out.3", dump("Client Request: accelbench cccc pid 7", "totals: 9"));
    EXPECT_EQ(read_callgrind_dump(out, "accelbench aaaa pid 7"), 600007u);
    EXPECT_EQ(read_callgrind_dump(out, "accelbench bbbb pid 7"), 1200007u);
    // Another file name, another process, or a prefix of a description: not ours.
    EXPECT_THROW(read_callgrind_dump(out, "accelbench cccc pid 7"), std::runtime_error);
    EXPECT_THROW(read_callgrind_dump(out, "accelbench aaaa pid 8"), std::runtime_error);
    EXPECT_THROW(read_callgrind_dump(out, "accelbench aaaa"), std::runtime_error);
    // No totals line: the summary's; neither: an error naming the file.
    write_file(dir.path(), "callgrind.out.4", "desc: Trigger: Client Request: accelbench dddd pid 7\nsummary: 42\n");
    EXPECT_EQ(read_callgrind_dump(out, "accelbench dddd pid 7"), 42u);
    write_file(dir.path(), "callgrind.out.5", "desc: Trigger: Client Request: accelbench eeee pid 7\n");
    EXPECT_THROW(read_callgrind_dump(out, "accelbench eeee pid 7"), std::runtime_error);
}

}  // namespace
}  // namespace accelbench
