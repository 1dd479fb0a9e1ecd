// The one argument parser (commands/args.h), and every command through it: --help prints
// the command's usage and exits 0; an unknown option is refused alike everywhere, exit 2.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "commands/args.h"
#include "commands/cli.h"

namespace accelbench {
namespace {

struct Outcome {
    std::optional<int> code;
    std::string out, err;
};

// Walks `argv` with the options of a small command: --flag, --name VALUE, --count N (1..9),
// positionals.
Outcome walk(std::vector<std::string> argv, bool& flag, std::string& name, int& count,
             std::vector<std::string>& positionals) {
    std::vector<char*> raw;
    for (auto& a : argv) raw.push_back(a.data());
    Args args("demo", "usage: accelbench demo [--flag] [--name X] [--count N] FILE...\n", int(raw.size()), raw.data());
    ::testing::internal::CaptureStdout();
    ::testing::internal::CaptureStderr();
    Outcome o;
    o.code = args.walk([&] {
        if (args.flag("--flag")) flag = true;
        else if (!(args.value("--name", name) || args.value("--count", count, 1, 9) || args.positional(positionals)))
            args.unknown();
    });
    o.out = ::testing::internal::GetCapturedStdout();
    o.err = ::testing::internal::GetCapturedStderr();
    return o;
}

TEST(Args, ReadsFlagsValuesInBothFormsAndPositionals) {
    bool flag = false;
    std::string name;
    int count = 0;
    std::vector<std::string> files;
    const Outcome o =
        walk({"a.csv", "--name", "x", "--flag", "--count=3", "b.csv", "--name=y=z"}, flag, name, count, files);
    EXPECT_FALSE(o.code) << o.err;
    EXPECT_TRUE(flag);
    EXPECT_EQ(name, "y=z");
    EXPECT_EQ(count, 3);
    EXPECT_EQ(files, (std::vector<std::string>{"a.csv", "b.csv"}));
    EXPECT_EQ(o.err, "");
}

TEST(Args, RefusesWhatItCannotFollowNamingIt) {
    bool flag = false;
    std::string name;
    int count = 0;
    std::vector<std::string> files;
    const std::pair<std::vector<std::string>, std::string> cases[] = {
        {{"--flg"}, "accelbench demo: unknown option '--flg'\nusage: accelbench demo"},
        {{"--name"}, "accelbench demo: --name needs a value\n"},
        {{"--name="}, "accelbench demo: --name needs a value, got an empty one\n"},
        {{"--name", ""}, "accelbench demo: --name needs a value, got an empty one\n"},
        {{"--count="}, "--count needs a value, got an empty one"},
        {{"--count", "10"}, "accelbench demo: --count expects an integer in [1, 9], got '10'\n"},
        {{"--count", "2x"}, "--count expects an integer in [1, 9], got '2x'"},
        {{"--flag=1"}, "unknown option '--flag=1'"},
    };
    for (const auto& [argv, message] : cases) {
        const Outcome o = walk(argv, flag, name, count, files);
        EXPECT_EQ(o.code, 2) << argv[0];
        EXPECT_NE(o.err.find(message), std::string::npos) << o.err;
        EXPECT_EQ(o.out, "");
    }
    const Outcome help = walk({"--name", "x", "--help", "--bogus"}, flag, name, count, files);
    EXPECT_EQ(help.code, 0);
    EXPECT_EQ(help.out, "usage: accelbench demo [--flag] [--name X] [--count N] FILE...\n");
}

// Every command of main.cpp's table answers --help with its usage (exit 0) and refuses an
// unknown option through the parser (exit 2), before doing anything.
TEST(Args, EveryCommandHasHelpAndRefusesAnUnknownOption) {
    const std::pair<const char*, int (*)(int, char**)> commands[] = {
        {"run", run_command},         {"merge", merge_command},
        {"render", render_command},   {"list", list_command},
        {"models", models_command},   {"provenance", provenance_command},
        {"columns", columns_command}, {"convert-csv", convert_csv_command},
    };
    for (const auto& [name, command] : commands) {
        std::string help = "--help", bogus = "--bogus";
        char* help_argv[] = {help.data()};
        char* bogus_argv[] = {bogus.data()};
        ::testing::internal::CaptureStdout();
        EXPECT_EQ(command(1, help_argv), 0) << name;
        const std::string out = ::testing::internal::GetCapturedStdout();
        EXPECT_NE(out.find(std::string("usage: accelbench ") + name), std::string::npos) << name << ": " << out;
        ::testing::internal::CaptureStderr();
        EXPECT_EQ(command(1, bogus_argv), 2) << name;
        const std::string err = ::testing::internal::GetCapturedStderr();
        EXPECT_EQ(err.rfind(std::string("accelbench ") + name + ": unknown option '--bogus'\n", 0), 0u) << err;
    }
}

}  // namespace
}  // namespace accelbench
