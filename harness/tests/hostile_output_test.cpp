// Hostile inputs aimed at what reaches a results file or standard output: numbers printed
// at the float limits, labels with control characters, ray sets too large together,
// --take-column's sources, a conversion beside files it did not write, and standard
// output that cannot be written. (Rows of another build under --resume, companion names
// and merge --shards without the config: hostile_input_test.cpp.) Each is generated here;
// each must be a clear refusal or, for good input, accepted.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "accelbench/base/params.h"
#include "commands/cli.h"
#include "config/ray_file.h"
#include "csv/csv.h"
#include "csv/results.h"
#include "csv/run_inputs.h"
#include "harness_test_util.h"

namespace accelbench {
namespace {

using namespace testing_util;
namespace fs = std::filesystem;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// What programs print for the float limits (shortest round trip: 3.4028235e38 is FLT_MAX,
// 1.1754944e-38 FLT_MIN) reads back as those floats; one past the rounding edge does not.
TEST(HostileOutputTest, FloatLimitsAsProgramsPrintThemAreAccepted) {
    for (const char* text : {"3.4028235e38", "-3.4028235e38", "3.40282347e38", "1.1754944e-38", "1.17549435e-38"})
        EXPECT_EQ(float_conversion_problem(std::strtod(text, nullptr), text), "") << text;
    EXPECT_EQ(round_to_float(3.4028235e38), std::numeric_limits<float>::max());
    EXPECT_EQ(round_to_float(1.17549435e-38), std::numeric_limits<float>::min());
    EXPECT_NE(float_conversion_problem(3.4028236e38, "3.4028236e38"), "");  // rounds to infinity
    EXPECT_NE(float_conversion_problem(1e-45, "1e-45"), "");                // a subnormal
    // A ray file whose tmax is FLT_MAX as printed, as a program writing rays would.
    TempDir dir("accelbench-hostile-output-");
    const std::string rays = write_file(dir.path(), "r.csv",
                                        "ox,oy,oz,dx,dy,dz,tmax\n0,0,1,0,0,-1,3.4028235e38\n"
                                        "0,0,-3.4028235e38,0,0,1,1\n");
    const RayFileContents got = read_ray_file(rays, "r.csv");
    ASSERT_TRUE(got.issues.empty()) << got.issues.front().message;
    ASSERT_EQ(got.rays.size(), 2u);
    EXPECT_EQ(got.rays[0].tmax, std::numeric_limits<float>::max());
    EXPECT_EQ(got.rays[1].org.z, -std::numeric_limits<float>::max());
}

TEST(HostileOutputTest, AControlCharacterInAModelLabelIsRefusedAtTheConfig) {
    TempDir dir("accelbench-hostile-output-");
    write_triangle_case(dir.path());
    for (const char* label : {R"("tri\nangle")", R"("bell\u0007")", R"("del\u007f")"}) {
        const ConfigError e = load_error(write_file(
            dir.path(), "c.yaml",
            std::string("models:\n  - {path: tri.obj, label: ") + label + "}\naccelerators: [{name: bvh}]\n"));
        EXPECT_TRUE(contains(all_issues(e), "holds the control character")) << label << all_issues(e);
    }
    // A model made from a path with a tab in its name gets the same refusal.
    write_file(dir.path(), "t\tab.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const ConfigError e = load_error(
        write_file(dir.path(), "p.yaml", "models:\n  - {path: \"t\\tab.obj\"}\naccelerators: [{name: bvh}]\n"));
    EXPECT_NE(all_issues(e).find("U+0009"), std::string::npos) << all_issues(e);
}

// Each set inside its own bound, all of them together over it: refused before any is made.
TEST(HostileOutputTest, RaySetsAreBoundedTogether) {
    TempDir dir("accelbench-hostile-output-");
    const ConfigError e = load_error(write_file(dir.path(), "sets.yaml", R"(render: {width: 2048, height: 2048}
ray_sets:
  sets: [primary, shadow, ao, diffuse]
  ao: {samples: 7}
  diffuse: {bounces: 7}
models: [stanford-bunny]
accelerators: [{name: embree}]
)"));
    EXPECT_EQ(e.issues().size(), 1u) << all_issues(e);
    EXPECT_TRUE(contains(all_issues(e), "ray_sets: the ray sets together hold 4294967296 bytes")) << all_issues(e);
    EXPECT_TRUE(contains(all_issues(e), "ao 1879048192")) << all_issues(e);
}

// --take-column: what it takes is declared, numbers only, from whole files, and the output
// equal to a source names that source.
class TakeColumnTest : public ::testing::Test {
protected:
    TempDir dir{"accelbench-hostile-output-"};
    static constexpr const char* kHeader =
        "combo_id,status,instructions,git_sha,git_dirty,compiler,build_type,compile_flags,cpu,embree_version,isa,"
        "embree_isa\n";
    const std::string prov = ",abc,false,gcc 12,Release,-O3,x,4.3,avx2,avx2\n";
    std::string write_run(const std::string& name, const std::string& rows) {
        const std::string p = write_file(dir.path(), name, kHeader + rows);
        write_inputs(p, {{"config", std::string(64, 'c'), "ci"}});
        return p;
    }
    std::string out() const { return (dir.path() / "out.csv").string(); }
    std::string refusal(const std::string& o, const std::string& in, const std::string& from,
                        const std::string& column = "instructions") {
        try {
            take_column(o, in, from, column, false);
        } catch (const std::runtime_error& e) {
            return e.what();
        }
        return "";
    }
};

TEST_F(TakeColumnTest, RefusesWhatWouldLeaveRowsContradictingThemselves) {
    const auto timed = write_run("timed.csv", "1,ok," + prov + "2,ok," + prov);
    write_file(dir.path(), "timed.reps.csv", "combo_id,repetition\n1,1\n2,1\n");
    EXPECT_TRUE(contains(refusal(out(), timed, write_run("nan.csv", "1,ok,lots" + prov)), "'lots' is not a finite"));
    EXPECT_TRUE(contains(refusal(out(), timed, write_run("inf.csv", "1,ok,inf" + prov)), "not a finite number"));
    EXPECT_TRUE(contains(refusal(out(), timed, timed, "status"), "column 'status' cannot be taken"));
    EXPECT_TRUE(contains(refusal(out(), timed, timed, "build_s_median"), "takeable: instructions"));
    // A cut last row (an interrupted run) in either file: refused, not dropped while its
    // repetitions are copied.
    const auto cut = write_run("cut.csv", "1,ok," + prov + "2,ok,,abc,fal");
    write_file(dir.path(), "cut.reps.csv", "combo_id,repetition\n1,1\n2,1\n");
    const auto cg = write_run("cg.csv", "1,ok,100" + prov);
    EXPECT_TRUE(contains(refusal(out(), cut, cg), "cut.csv: the last line is incomplete"));
    EXPECT_TRUE(contains(refusal(out(), timed, cut), "cut.csv: the last line is incomplete"));
    EXPECT_FALSE(fs::exists(out()));
    // OUT equal to FROM (or IN) is named as such, not blamed on another process's lock.
    const std::string same = refusal(cg, timed, cg);
    EXPECT_TRUE(contains(same, "is also the input FROM")) << same;
    EXPECT_FALSE(contains(same, "another process")) << same;
    EXPECT_TRUE(contains(refusal(timed, timed, cg), "is also the input IN"));
    EXPECT_EQ(take_column(out(), timed, cg, "instructions", false), 1u);
}

// NEW.inputs.csv that was there before the conversion (another run's record) stays.
TEST(HostileOutputTest, ConvertCsvTouchesNoFileItDidNotWrite) {
    TempDir dir("accelbench-hostile-output-");
    const auto old_csv =
        write_file(dir.path(), "old.csv", "config,combo_id,accel,params,split,status,tree_depth\nt,1,bvh,,sah,ok,7\n");
    const std::string new_csv = (dir.path() / "new.csv").string();
    const std::string record = write_file(dir.path(), "new.inputs.csv", "kind,sha256,name\nconfig,abc,other-run\n");
    EXPECT_THROW(convert_results(old_csv, new_csv), std::runtime_error);
    EXPECT_EQ(read_file(record), "kind,sha256,name\nconfig,abc,other-run\n");
    EXPECT_FALSE(fs::exists(new_csv));
    fs::remove(record);
    EXPECT_EQ(convert_results(old_csv, new_csv), 1u);
    EXPECT_FALSE(fs::exists(record));                         // OLD has no record: none is made
    EXPECT_FALSE(fs::exists((dir.path() / "new.reps.csv")));  // nor repetitions
}

// The exit status of a command whose standard output did not arrive, in a child process
// whose stdout is `fd` (SIGPIPE ignored, as under a parent that ignores it).
int status_writing_to(int fd) {
    std::fflush(stdout);
    const pid_t pid = fork();
    if (pid == 0) {
        std::signal(SIGPIPE, SIG_IGN);
        dup2(fd, STDOUT_FILENO);
        for (int i = 0; i < 1000; ++i) std::printf("a line of a listing that must all arrive\n");
        _exit(with_output_checked("test", 0));
    }
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

TEST(HostileOutputTest, AFailedWriteToStandardOutputIsAnError) {
    const int full = open("/dev/full", O_WRONLY);
    ASSERT_GE(full, 0);
    EXPECT_EQ(status_writing_to(full), 1);
    close(full);
    int fds[2];
    ASSERT_EQ(pipe(fds), 0);
    close(fds[0]);  // nobody reads: EPIPE
    EXPECT_EQ(status_writing_to(fds[1]), 1);
    close(fds[1]);
    const int null = open("/dev/null", O_WRONLY);
    EXPECT_EQ(status_writing_to(null), 0);
    close(null);
}

}  // namespace
}  // namespace accelbench
