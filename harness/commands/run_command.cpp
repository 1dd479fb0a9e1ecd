#include "commands/args.h"
#include "commands/cli.h"

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
    "  --dry-run=json        the same as one JSON document, with each accelerator entry's axes (ranges\n"
    "                        expanded, canonical values): for programs, such as the grid search\n"
    "  --out FILE            results CSV (default results/runs/<name>-<timestamp>.csv); repetitions go\n"
    "                        beside it in FILE minus .csv plus .reps.csv\n"
    "  --resume              append to the output file, skipping combinations already in it (without\n"
    "                        --out: the newest results/runs/<name>-*.csv of this shard)\n"
    "  --allow-mixed         with --resume: append even to rows another build or machine measured (they\n"
    "                        differ in git_sha, git_dirty, compiler, build_type, isa, embree_version or cpu)\n"
    "  --shard I/N           run only shard I (0-based) of N, chosen by a hash of each combination;\n"
    "                        default from SLURM_ARRAY_TASK_ID / SLURM_ARRAY_TASK_COUNT\n"
    "  --plugin PATH         load the structures of a plugin (accelbench_plugin.h); repeatable, like\n"
    "                        the config's `plugins:`\n"
    "  --in-process          measure in this process (no fork: for debuggers and profilers; a time\n"
    "                        limit is then checked only between repetitions, and a crash ends the run)\n"
    "  --show-repetitions    print every repetition, not only Google Benchmark's aggregates\n"
    "  --instructions OUT    under valgrind --tool=callgrind --instr-atstart=no --callgrind-out-file=OUT:\n"
    "                        count the instructions of one render per combination (column instructions)\n"
    "  --benchmark_out=FILE  also write Google Benchmark's JSON (for compare.py); other --benchmark_*\n"
    "                        flags go to Google Benchmark\n";

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
            print_dry_run(plan, opt.dry_run_json);
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
        return usage_error("run", kRunUsage, e.what());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench run: %s\n", e.what());
        return 2;
    }
}

}  // namespace

int run_command(int argc, char** argv) {
    RunOptions opt;
    std::vector<std::string> configs;
    std::string shard, plugin;
    std::vector<std::string> plugins;
    Args args("run", kRunUsage, argc, argv);
    const auto each = [&] {
        const std::string& a = args.current();
        if (args.flag("--dry-run")) opt.dry_run = true;
        else if (args.flag("--dry-run=json")) opt.dry_run = opt.dry_run_json = true;
        else if (args.flag("--resume")) opt.resume = true;
        else if (args.flag("--allow-mixed")) opt.allow_mixed = true;
        else if (args.flag("--in-process")) opt.in_process = true;
        else if (args.flag("--show-repetitions")) opt.show_repetitions = true;
        else if (args.value("--out", opt.out) || args.value("--instructions", opt.callgrind_out)) return;
        else if (args.value("--plugin", plugin)) plugins.push_back(plugin);
        else if (args.value("--shard", shard)) opt.shard = parse_shard(shard);
        else if (args.value("--benchmark_out", opt.json_out)) return;
        else if (a.rfind("--benchmark_out_format=", 0) == 0) {
            if (a.substr(23) != "json")
                throw ArgError("only --benchmark_out_format=json is supported (our own CSV is the results file)");
            args.take();
        } else if (a.rfind("--benchmark_filter", 0) == 0 || a.rfind("--benchmark_list_tests", 0) == 0)
            throw ArgError(a + ": choose combinations in the config (or with --shard) instead");
        else if (a.rfind("--benchmark_", 0) == 0) opt.benchmark_args.push_back(args.take());
        else if (args.positional(configs)) {
            if (configs.size() > 1)
                throw ArgError("one config at a time (got '" + configs[0] + "' and '" + configs[1] + "')");
        } else args.unknown();
    };
    try {
        if (auto code = args.walk(each)) return *code;
    } catch (const std::invalid_argument& e) {  // parse_shard
        return args.error(e.what());
    }
    if (configs.empty()) return args.error("no config given");
    if (auto code = load_plugins("run", plugins)) return *code;
    opt.config_path = configs[0];
    if (!opt.callgrind_out.empty() && !opt.dry_run && !running_on_valgrind())
        return args.error(
            "--instructions counts with callgrind: run under valgrind --tool=callgrind "
            "--instr-atstart=no --callgrind-out-file=" +
            opt.callgrind_out);
    if (opt.resume && opt.out.empty() && opt.dry_run) return args.error("--resume and --dry-run do not go together");
    return run(opt);
}

}  // namespace accelbench
