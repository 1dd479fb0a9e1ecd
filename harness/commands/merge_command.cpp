// `accelbench merge`: result files (shards) joined into one, or one column taken from
// another run of the same config (--take-column).
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "accelbench/base/params.h"
#include "commands/args.h"
#include "commands/cli.h"
#include "csv/results.h"
#include "plan/combinations.h"
#include "plan/shard_check.h"

namespace accelbench {

namespace {

const char* kMergeUsage =
    "usage: accelbench merge [--allow-mixed] [--config CONFIG.yaml [--shards N]] OUT.csv IN.csv...\n"
    "       accelbench merge [--allow-mixed] --take-column COLUMN OUT.csv IN.csv FROM.csv\n"
    "  joins result files (e.g. shards) and their .reps.csv files; refuses inputs whose\n"
    "  build or machine (git_sha, git_dirty, compiler, build_type, isa, embree_version, cpu:\n"
    "  the rule run --resume and the analysis share), config or record of inputs\n"
    "  (NAME.inputs.csv: sha256 of the config, mesh\n"
    "  and ray files) differs, or that have no such record, unless --allow-mixed; a\n"
    "  combination present in two inputs;\n"
    "  and an input a run is still writing (it holds the file's lock).\n"
    "  --config: also refuses (exit 3, nothing written) unless every combination of CONFIG\n"
    "  is in an input, naming the missing ones by their shard of N (--shards, default 1),\n"
    "  and refuses rows that are not of CONFIG or measured from other contents than it has now\n"
    "  --take-column: OUT is IN with COLUMN's values taken from FROM by combo_id (the\n"
    "  instructions of a callgrind run added to a timed run of the same config); COLUMN is one\n"
    "  of: instructions; FROM's values must be numbers, neither file may end in a cut row\n";

// OUT.csv is IN.csv with `column` taken from FROM.csv.
int take_one_column(const std::vector<std::string>& files, const std::string& column, bool allow_mixed) {
    if (files.size() != 3) return usage_error("merge", kMergeUsage, "--take-column needs OUT.csv IN.csv FROM.csv");
    try {
        const size_t n = take_column(files[0], files[1], files[2], column, allow_mixed);
        std::fprintf(stderr, "accelbench merge: %s written with %s of %zu rows taken from %s\n", files[0].c_str(),
                     column.c_str(), n, files[2].c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench merge: %s\n", e.what());
        return 2;
    }
    return 0;
}

}  // namespace

int merge_command(int argc, char** argv) {
    bool allow_mixed = false;
    std::string take, config_path, shards_text;
    std::vector<std::string> files;
    Args args("merge", kMergeUsage, argc, argv);
    if (auto code = args.walk([&] {
            if (args.flag("--allow-mixed")) allow_mixed = true;
            else if (args.value("--take-column", take) || args.value("--config", config_path) ||
                     args.value("--shards", shards_text) || args.positional(files))
                return;
            else args.unknown();
        }))
        return *code;
    uint64_t shards = 1;
    if (!shards_text.empty()) {
        try {
            shards = parse_shard("0/" + shards_text).count;
        } catch (const std::invalid_argument&) {
            const std::string form = number_form_problem(shards_text);  // "02": the number rule's words
            return args.error("--shards expects a count > 0, got '" + shards_text + "'" +
                              (form.empty() ? "" : ": " + form));
        }
    }
    if (files.size() < 2) return args.error("give OUT.csv and at least one IN.csv");
    // The shard count only means something against a config's combinations: without one,
    // nothing would be checked and the merge would look checked.
    if (!shards_text.empty() && config_path.empty())
        return args.error("--shards " + shards_text + " needs --config CONFIG.yaml (the combinations to check)");
    if (!take.empty() && (!config_path.empty() || !shards_text.empty()))
        return args.error("--take-column does not check shards: give it without --config and --shards");
    if (!take.empty()) return take_one_column(files, take, allow_mixed);
    if (!config_path.empty())
        if (int rc = check_shards_complete(config_path, shards, {files.begin() + 1, files.end()}, allow_mixed); rc != 0)
            return rc;
    try {
        const size_t rows = merge_results(files[0], {files.begin() + 1, files.end()}, allow_mixed);
        std::fprintf(stderr, "accelbench merge: %zu rows from %zu files written to %s\n", rows, files.size() - 1,
                     files[0].c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench merge: %s\n", e.what());
        return 2;
    }
    return 0;
}

}  // namespace accelbench
