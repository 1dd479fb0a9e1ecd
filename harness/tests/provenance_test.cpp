// git_sha and git_dirty are the provenance of the code that was compiled, stamped at build
// time (harness/scripts/provenance_stamp.cmake): what git says when the binary runs does
// not change them, and every build stamps them again from the tree as it is then.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "csv/provenance.h"
#include "harness_test_util.h"

namespace fs = std::filesystem;

namespace accelbench {
namespace {

using namespace testing_util;

const std::string kFakeSha(40, 'f');

// A process's provenance is gathered once, on first use: this test is its own process
// (ctest runs each test alone), so nothing has asked before the environment is changed.
TEST(ProvenanceStampTest, ARunTimeGitDoesNotChangeIt) {
    TempDir dir("accelbench-provenance-test-");
    // Another git first on PATH, answering every question with a commit and a change.
    const std::string git = write_file(
        dir.path(), "git", "#!/bin/sh\ncase \"$*\" in *status*) echo ' M x';; *) echo " + kFakeSha + ";; esac\n");
    ::chmod(git.c_str(), 0755);
    const std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
    ::setenv("PATH", (dir.path().string() + ":" + path).c_str(), 1);
    ::setenv("GIT_DIR", (dir.path() / "elsewhere").c_str(), 1);
    const Provenance& p = provenance();
    EXPECT_NE(p.git_sha, kFakeSha);
    EXPECT_TRUE(p.git_sha == "unknown" ||
                (p.git_sha.size() == 40 && p.git_sha.find_first_not_of("0123456789abcdef") == std::string::npos))
        << p.git_sha;
    ::setenv("PATH", path.c_str(), 1);
    ::unsetenv("GIT_DIR");
}

// The stamp script on a repository of its own: the commit, then each kind of change.
class StampScriptTest : public ::testing::Test {
protected:
    TempDir dir{"accelbench-stamp-test-"};
    fs::path repo = dir.path() / "repo", out = dir.path() / "stamp.cpp";

    int sh(const std::string& cmd) {
        return std::system(("cd '" + repo.string() + "' && " + cmd + " >/dev/null 2>&1").c_str());
    }
    // Runs the script; returns the stamp's text.
    std::string stamp() {
        const char* src = std::getenv("ACCELBENCH_SOURCE_DIR");
        const std::string script = (fs::path(src ? src : ".") / "harness/scripts/provenance_stamp.cmake").string();
        EXPECT_EQ(std::system(("cmake -DSOURCE_DIR='" + repo.string() + "' -DOUT='" + out.string() + "' -P '" + script +
                               "' >/dev/null")
                                  .c_str()),
                  0);
        return read_file(out.string());
    }
    std::string head() {
        const fs::path f = dir.path() / "head";
        EXPECT_EQ(std::system(("git -C '" + repo.string() + "' rev-parse HEAD > '" + f.string() + "'").c_str()), 0);
        std::string s = read_file(f.string());
        return s.substr(0, s.find('\n'));
    }
};

TEST_F(StampScriptTest, DirtyIsTheCompiledSourcesAgainstTheCommit) {
    fs::create_directories(repo / "core");
    fs::create_directories(repo / "results");
    write_file(repo / "core", "a.cpp", "int a;\n");
    write_file(repo / "results", "r.csv", "x\n");
    ASSERT_EQ(sh("git init -q && git add . && git -c user.name=t -c user.email=t@t commit -qm c"), 0);
    const std::string clean = stamp();
    EXPECT_NE(clean.find("kBuildGitSha = \"" + head() + "\""), std::string::npos) << clean;
    EXPECT_NE(clean.find("kBuildGitDirty = false"), std::string::npos) << clean;

    // Rewritten only when it changes: an unchanged tree recompiles nothing.
    const auto written = fs::last_write_time(out);
    fs::last_write_time(out, written - std::chrono::hours(1));
    stamp();
    EXPECT_EQ(fs::last_write_time(out), written - std::chrono::hours(1));

    write_file(repo / "results", "r.csv", "y\n");  // an output, not code
    EXPECT_NE(stamp().find("kBuildGitDirty = false"), std::string::npos);
    write_file(repo, "notes.txt", "mine\n");  // untracked and not compiled
    EXPECT_NE(stamp().find("kBuildGitDirty = false"), std::string::npos);
    write_file(repo / "core", "b.cpp", "int b;\n");  // untracked, but the build compiles it
    EXPECT_NE(stamp().find("kBuildGitDirty = true"), std::string::npos);
    fs::remove(repo / "core" / "b.cpp");
    write_file(repo / "core", "a.cpp", "int a = 1;\n");  // a tracked source changed
    EXPECT_NE(stamp().find("kBuildGitDirty = true"), std::string::npos);
    ASSERT_EQ(sh("git -c user.name=t -c user.email=t@t commit -qam d"), 0);
    const std::string committed = stamp();
    EXPECT_NE(committed.find("kBuildGitSha = \"" + head() + "\""), std::string::npos) << committed;
    EXPECT_NE(committed.find("kBuildGitDirty = false"), std::string::npos) << committed;

    // GIT_DIR pointing elsewhere at build time does not change what is stamped.
    ::setenv("GIT_DIR", (dir.path() / "elsewhere").c_str(), 1);
    EXPECT_EQ(stamp(), committed);
    ::unsetenv("GIT_DIR");

    fs::remove_all(repo / ".git");  // not a checkout
    const std::string none = stamp();
    EXPECT_NE(none.find("kBuildGitSha = \"unknown\""), std::string::npos) << none;
}

}  // namespace
}  // namespace accelbench
