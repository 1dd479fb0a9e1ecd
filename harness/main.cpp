// accelbench: the command line. A thin dispatcher; each subcommand lives in its own file.
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "accelbench/base/memory.h"
#include "commands/cli.h"
#include "csv/provenance.h"
#include "csv/results.h"

namespace {

struct Command {
    const char* name;
    int (*run)(int, char**);
    const char* help;
};

const Command kCommands[] = {
    {"run", accelbench::run_command, "measure a config (configs/*.yaml): combinations, Google Benchmark, results CSV"},
    {"merge", accelbench::merge_command, "join result files (shards) that share a provenance"},
    {"render", accelbench::render_command, "render one model with one accelerator, print what it measured"},
    {"list", accelbench::list_command,
     "accelerators with their parameters and defaults; procedural scenes (--json: the structure table)"},
    {"models", accelbench::models_command, "the model registry: where each file was found (--fetch: download missing)"},
    {"provenance", accelbench::provenance_command, "the provenance columns this build writes into every results row"},
    {"columns", accelbench::columns_command, "the results CSV's columns: name, kind, unit and what each holds"},
    {"convert-csv", accelbench::convert_csv_command, "rename an old results file's columns (OLD NEW), checked"},
};

// `accelbench --version`: the build's identity as its rows record it (the project has no
// release numbers: the commit is the version).
int version() {
    std::string sha, dirty, compiler, build_type, flags;
    for (const auto& [name, value] : accelbench::provenance_values()) {
        if (name == "git_sha") sha = value;
        if (name == "git_dirty") dirty = value;
        if (name == "compiler") compiler = value;
        if (name == "build_type") build_type = value;
        if (name == "compile_flags") flags = value;
    }
    std::printf("accelbench commit %s%s, %s build (%s), %s\n", sha.c_str(),
                dirty == "true" ? " (with uncommitted changes)" : "", build_type.c_str(), flags.c_str(),
                compiler.c_str());
    return 0;
}

int usage(FILE* to) {
    std::fprintf(to, "usage: accelbench COMMAND [ARGS] | --version\n\ncommands:\n");
    for (const auto& c : kCommands) std::fprintf(to, "  %-11s %s\n", c.name, c.help);
    return to == stdout ? 0 : 2;
}

}  // namespace

int main(int argc, char** argv) {
    // Before anything is allocated: a combination's build must not depend on what the
    // process freed before it (base/memory.h), here or in the children forked to measure.
    accelbench::fix_malloc_thresholds();
    // A column name twice would be read wrongly by every CSV reader but ours: refuse to
    // start rather than write such a file.
    try {
        accelbench::check_column_names(accelbench::result_column_table());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench: %s\n", e.what());
        return 2;
    }
    if (argc < 2) return usage(stderr);
    if (!std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "help"))
        return accelbench::with_output_checked("help", usage(stdout));
    if (!std::strcmp(argv[1], "--version")) return accelbench::with_output_checked("--version", version());
    for (const auto& c : kCommands)
        if (!std::strcmp(argv[1], c.name)) return accelbench::with_output_checked(c.name, c.run(argc - 2, argv + 2));
    std::fprintf(stderr, "accelbench: unknown command '%s'\n", argv[1]);
    return usage(stderr);
}
