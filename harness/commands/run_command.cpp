#include "commands/run_command.h"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "csv/results.h"
#include "plan/run_plan.h"
#include "plan/shard_check.h"
#include "run/instructions.h"
#include "run/runner.h"
#include "sinks/json_output.h"
#include "sinks/progress.h"
#include "sinks/repetitions_csv.h"
#include "sinks/results_csv.h"
#include "sinks/verdict_table.h"

namespace accelbench {

namespace {

const char* kRunUsage =
    "usage: accelbench run [options] CONFIG.yaml\n"
    "  --dry-run             print the expanded combinations and their count; measure nothing\n"
    "  --out FILE            results CSV (default results/runs/<name>-<timestamp>.csv); repetitions go\n"
    "                        beside it in FILE minus .csv plus .reps.csv\n"
    "  --resume              append to the output file, skipping combinations already in it (without\n"
    "                        --out: the newest results/runs/<name>-*.csv of this shard)\n"
    "  --shard I/N           run only shard I (0-based) of N, chosen by a hash of each combination;\n"
    "                        default from SLURM_ARRAY_TASK_ID / SLURM_ARRAY_TASK_COUNT\n"
    "  --in-process          measure in this process (no fork: for debuggers and profilers; a time\n"
    "                        limit is then checked only between repetitions, and a crash ends the run)\n"
    "  --show-repetitions    print every repetition, not only Google Benchmark's aggregates\n"
    "  --instructions OUT    under valgrind --tool=callgrind --instr-atstart=no --callgrind-out-file=OUT:\n"
    "                        count the instructions of one render per combination (column instructions)\n"
    "  --benchmark_out=FILE  also write Google Benchmark's JSON (for compare.py); other --benchmark_*\n"
    "                        flags go to Google Benchmark\n";

int usage_error(const std::string& msg) {
    std::fprintf(stderr, "accelbench run: %s\n%s", msg.c_str(), kRunUsage);
    return 2;
}

// Google Benchmark's own flags (all but --benchmark_out, which this process owns). The
// arguments outlive the call: GB keeps argv[0] for its context line ("Running ...").
void initialize_google_benchmark(const std::vector<std::string>& benchmark_args) {
    static std::vector<std::string> gb_args;
    gb_args = {"accelbench run"};
    gb_args.insert(gb_args.end(), benchmark_args.begin(), benchmark_args.end());
    std::vector<char*> gb_argv;
    for (auto& a : gb_args) gb_argv.push_back(a.data());
    int gb_argc = int(gb_argv.size());
    benchmark::Initialize(&gb_argc, gb_argv.data());
    if (gb_argc > 1) throw UsageError(std::string("unknown Google Benchmark flag '") + gb_argv[1] + "'");
}

// Plan, then the sinks in the order each result reaches them (the repetitions before the
// results row: a run killed between them leaves repetitions that --resume drops), then run.
int run(const RunOptions& opt) {
    try {
        RunPlan plan = plan_run(opt);
        if (opt.dry_run) {
            print_dry_run(plan);
            return 0;
        }
        initialize_google_benchmark(opt.benchmark_args);
        // The JSON file first: one that cannot be written is refused before the results
        // file is made (or locked) or anything measured.
        std::optional<JsonOutput> json;
        if (!opt.json_out.empty()) json.emplace(opt.json_out);
        choose_output(plan, opt);
        ResultsCsv results(plan.out);
        RepetitionsCsv repetitions(repetitions_path(plan.out));
        VerdictTable verdicts;
        Progress progress;
        std::vector<RunSink*> sinks;
        if (json) sinks.push_back(&*json);
        for (RunSink* s : std::initializer_list<RunSink*>{&verdicts, &progress, &repetitions, &results})
            sinks.push_back(s);
        return run_plan(plan, opt, sinks);
    } catch (const ConfigError& e) {
        for (const auto& issue : e.issues()) std::fprintf(stderr, "%s\n", format_issue(issue).c_str());
        std::fprintf(stderr, "accelbench run: %zu error%s in %s; nothing was run\n", e.issues().size(),
                     e.issues().size() == 1 ? "" : "s", opt.config_path.c_str());
        return 2;
    } catch (const UsageError& e) {
        return usage_error(e.what());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench run: %s\n", e.what());
        return 2;
    }
}

}  // namespace

int run_command(int argc, char** argv) {
    RunOptions opt;
    for (int i = 0; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
            return argv[++i];
        };
        try {
            if (a == "-h" || a == "--help") {
                std::printf("%s", kRunUsage);
                return 0;
            } else if (a == "--dry-run") opt.dry_run = true;
            else if (a == "--resume") opt.resume = true;
            else if (a == "--in-process") opt.in_process = true;
            else if (a == "--show-repetitions") opt.show_repetitions = true;
            else if (a == "--out") opt.out = value();
            else if (a == "--instructions") opt.callgrind_out = value();
            else if (a == "--shard") opt.shard = parse_shard(value());
            else if (a.rfind("--benchmark_out=", 0) == 0) opt.json_out = a.substr(16);
            else if (a.rfind("--benchmark_out_format=", 0) == 0) {
                if (a.substr(23) != "json")
                    return usage_error(
                        "only --benchmark_out_format=json is supported (our own CSV is the results file)");
            } else if (a.rfind("--benchmark_filter", 0) == 0 || a.rfind("--benchmark_list_tests", 0) == 0)
                return usage_error(a + ": choose combinations in the config (or with --shard) instead");
            else if (a.rfind("--benchmark_", 0) == 0) opt.benchmark_args.push_back(a);
            else if (a.rfind("-", 0) == 0) return usage_error("unknown option '" + a + "'");
            else if (opt.config_path.empty()) opt.config_path = a;
            else return usage_error("one config at a time (got '" + opt.config_path + "' and '" + a + "')");
        } catch (const std::invalid_argument& e) {
            return usage_error(e.what());
        }
    }
    if (opt.config_path.empty()) return usage_error("no config given");
    if (!opt.callgrind_out.empty() && !opt.dry_run && !running_on_valgrind())
        return usage_error(
            "--instructions counts with callgrind: run under valgrind --tool=callgrind "
            "--instr-atstart=no --callgrind-out-file=" +
            opt.callgrind_out);
    if (opt.resume && opt.out.empty() && opt.dry_run) return usage_error("--resume and --dry-run do not go together");
    return run(opt);
}

int merge_command(int argc, char** argv) {
    bool allow_mixed = false;
    std::string take, config_path;
    uint64_t shards = 1;
    std::vector<std::string> files;
    for (int i = 0; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--allow-mixed") allow_mixed = true;
        else if (a == "--take-column" && i + 1 < argc) take = argv[++i];
        else if (a == "--config" && i + 1 < argc) config_path = argv[++i];
        else if (a == "--shards" && i + 1 < argc) {
            try {
                shards = parse_shard("0/" + std::string(argv[++i])).count;
            } catch (const std::invalid_argument&) {
                std::fprintf(stderr, "accelbench merge: --shards expects a count > 0, got '%s'\n", argv[i]);
                return 2;
            }
        } else if (a == "-h" || a == "--help") {
            std::printf(
                "usage: accelbench merge [--allow-mixed] [--config CONFIG.yaml [--shards N]] OUT.csv IN.csv...\n"
                "       accelbench merge [--allow-mixed] --take-column COLUMN OUT.csv IN.csv FROM.csv\n"
                "  joins result files (e.g. shards) and their .reps.csv files; refuses inputs whose\n"
                "  provenance (git_sha, git_dirty, compiler, build_type, cpu, embree_version, isa), config\n"
                "  or record of inputs (NAME.inputs.csv: sha256 of the config, mesh and ray files) differs,\n"
                "  or that have no such record, unless --allow-mixed; a combination present in two inputs;\n"
                "  and an input a run is still writing (it holds the file's lock).\n"
                "  --config: also refuses (exit 3, nothing written) unless every combination of CONFIG\n"
                "  is in an input, naming the missing ones by their shard of N (--shards, default 1),\n"
                "  and refuses rows that are not of CONFIG or measured from other contents than it has now\n"
                "  --take-column: OUT is IN with COLUMN's values taken from FROM by combo_id (e.g. the\n"
                "  instructions of a callgrind run added to a timed run of the same config)\n");
            return 0;
        } else if (a.rfind("-", 0) == 0) {
            std::fprintf(stderr, "accelbench merge: unknown option '%s'\n", a.c_str());
            return 2;
        } else files.push_back(a);
    }
    if (files.size() < 2) {
        std::fprintf(stderr, "accelbench merge: usage: accelbench merge [--allow-mixed] OUT.csv IN.csv...\n");
        return 2;
    }
    if (!take.empty()) {
        if (files.size() != 3) {
            std::fprintf(stderr, "accelbench merge: --take-column needs OUT.csv IN.csv FROM.csv\n");
            return 2;
        }
        try {
            const size_t n = take_column(files[0], files[1], files[2], take, allow_mixed);
            std::fprintf(stderr, "accelbench merge: %s written with %s of %zu rows taken from %s\n", files[0].c_str(),
                         take.c_str(), n, files[2].c_str());
        } catch (const std::exception& e) {
            std::fprintf(stderr, "accelbench merge: %s\n", e.what());
            return 2;
        }
        return 0;
    }
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
