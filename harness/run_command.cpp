#include "run_command.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "accelbench/accel/registry.h"
#include "combinations.h"
#include "config.h"
#include "instructions.h"
#include "loaded_model.h"
#include "measure.h"
#include "model_registry.h"
#include "provenance.h"
#include "results.h"
#include "stats.h"
#include "text.h"
#include "verdicts.h"

namespace fs = std::filesystem;

namespace accelbench {

namespace {

using Clock = std::chrono::steady_clock;

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

std::string utc_now(const char* format) {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[64];
    std::strftime(buf, sizeof buf, format, &tm);
    return buf;
}

std::string num(double v, int digits = 9) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

std::string clock_text(double s) {
    const long t = long(s + 0.5);
    char buf[32];
    if (t >= 3600) std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
    else std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
    return buf;
}

std::string shard_suffix(const std::optional<Shard>& s) {
    return s && s->count > 1 ? "-shard" + std::to_string(s->index) + "of" + std::to_string(s->count) : "";
}

// The newest results/runs/<name>-<timestamp><shard>.csv.
std::optional<std::string> newest_run(const std::string& dir, const std::string& name, const std::string& suffix) {
    if (!fs::is_directory(dir)) return std::nullopt;
    std::string escaped;
    for (char ch : name + "\x01" + suffix) {
        if (ch == '\x01') escaped += "-[0-9]{8}-[0-9]{6}";
        else if (std::strchr(".^$|()[]{}*+?\\-", ch)) escaped += std::string("\\") + ch;
        else escaped += ch;
    }
    const std::regex pattern(escaped + "\\.csv");
    std::optional<std::string> best;
    for (const auto& e : fs::directory_iterator(dir)) {
        const std::string file = e.path().filename().string();
        if (std::regex_match(file, pattern) && (!best || file > fs::path(*best).filename().string()))
            best = e.path().string();
    }
    return best;
}

// Google Benchmark's JSON for the whole run, assembled from each combination's run
// objects (they are measured in child processes, which must not write the file).
class JsonOutput {
public:
    explicit JsonOutput(const std::string& path) : file_(path, std::ios::trunc) {
        if (!file_) throw std::runtime_error("cannot open '" + path + "' for --benchmark_out");
        reporter_.SetOutputStream(&file_);
        reporter_.SetErrorStream(&std::cerr);
        benchmark::BenchmarkReporter::Context context;
        context.name_field_width = 0;
        reporter_.ReportContext(context);
    }
    ~JsonOutput() { reporter_.Finalize(); }
    void add(const std::string& runs) {
        if (runs.empty()) return;
        if (!first_) file_ << ",\n";
        file_ << runs;
        file_.flush();
        first_ = false;
    }

private:
    std::ofstream file_;
    benchmark::JSONReporter reporter_;
    bool first_ = true;
};

// The columns every row of a combination has, whatever its status.
Row base_row(const Config& config, const Combination& c, std::optional<uint64_t> triangles,
             std::optional<uint64_t> vertices) {
    const ModelSpec& model = config.models[c.model];
    const Provenance& p = provenance();
    Row r;
    r["config"] = config.name;
    r["combo_id"] = c.id;
    r["model"] = model.label;
    if (triangles) r["triangles"] = std::to_string(*triangles);
    if (vertices) r["vertices"] = std::to_string(*vertices);
    const bool judged = model.kind == ModelSpec::Kind::Case;  // its own rays; no image, no shadow rays
    r["ray_source"] = judged ? "robustness-case" : model.rays ? model.rays->display : "camera";
    r["accel"] = c.accel;
    r["params"] = c.params.canonical();
    for (const auto& [k, v] : c.params.items()) r[param_column(k)] = v;
    if (!model.rays && !judged) {
        r["width"] = std::to_string(config.render.width);
        r["height"] = std::to_string(config.render.height);
        r["spp"] = std::to_string(config.render.spp);
    }
    if (!judged) {
        r["light"] = config.render.light ? "true" : "false";
        r["shading"] = config.render.shading ? "true" : "false";
    }
    r["git_sha"] = p.git_sha;
    r["git_dirty"] = p.git_dirty ? "true" : "false";
    r["compiler"] = p.compiler;
    r["build_type"] = p.build_type;
    r["cpu"] = p.cpu;
    r["threads"] = std::to_string(config.render.threads);
    r["embree_version"] = p.embree_version;
    r["timestamp"] = utc_now("%Y-%m-%dT%H:%M:%SZ");
    r["isa"] = p.isa;
    return r;
}

void add_measurement(Row& r, const Measurement& m) {
    r["status"] = m.status;
    r["message"] = m.message;
    if (m.status != "ok") return;  // nothing that could be mistaken for a result
    for (const auto& [k, v] : m.columns) r[k] = v;
    if (m.render_s.empty()) {  // a judged robustness case: a verdict, no timing
        r["rays"] = std::to_string(m.rays);
        for (const auto& f : build_stat_fields())
            if (auto v = f.get(m.build)) r[f.name] = std::to_string(uint64_t(*v));
        return;
    }
    r["repetitions"] = std::to_string(m.render_s.size());
    for (auto [prefix, samples] : {std::pair<std::string, const std::vector<double>*>{"build_s", &m.build_s},
                                   {"render_s", &m.render_s}}) {
        const Summary s = summarize(*samples);
        r[prefix + "_median"] = num(s.median);
        r[prefix + "_mean"] = num(s.mean);
        if (s.stddev) r[prefix + "_stddev"] = num(*s.stddev);
        if (s.ci_lo) r[prefix + "_ci_lo"] = num(*s.ci_lo);
        if (s.ci_hi) r[prefix + "_ci_hi"] = num(*s.ci_hi);
        if (s.coverage) r["ci_coverage"] = num(*s.coverage, 6);
    }
    r["rays"] = std::to_string(m.rays);
    r["hits"] = std::to_string(m.hits);
    r["shadow_rays"] = std::to_string(m.shadow_rays);
    r["shadow_hits"] = std::to_string(m.shadow_hits);
    const uint64_t all_rays = m.rays + m.shadow_rays;
    r["mrays_per_s"] = num(double(all_rays) / summarize(m.render_s).median * 1e-6, 6);
    for (const auto& f : build_stat_fields())
        if (auto v = f.get(m.build)) r[f.name] = f.count ? std::to_string(*(m.build.*f.count)) : num(*v, 12);
    std::string extra;
    for (const auto& [k, v] : m.build.extra) append_item(extra, ";", k, "=", num(v));
    r["build_extra"] = extra;
    if (m.counts) {
        r["prim_tests"] = std::to_string(m.counts->prim_tests);
        r["node_visits"] = std::to_string(m.counts->node_visits);
        r["box_tests"] = std::to_string(m.counts->box_tests);
        if (all_rays) {
            r["prim_tests_per_ray"] = num(double(m.counts->prim_tests) / double(all_rays), 6);
            r["node_visits_per_ray"] = num(double(m.counts->node_visits) / double(all_rays), 6);
        }
    }
    if (m.instructions) r["instructions"] = std::to_string(*m.instructions);
}

struct RunOptions {
    std::string config_path;
    bool dry_run = false, resume = false, in_process = false, show_repetitions = false;
    std::string out, json_out, callgrind_out;
    std::optional<Shard> shard;
    std::vector<std::string> benchmark_args;
};

void print_dry_run(const Config& config, const std::vector<Combination>& all, const std::vector<const Combination*>& selected,
                   const std::optional<Shard>& shard, const ModelRegistry& registry) {
    // Triangle counts decide the skip rules: the registry knows them; other models are
    // generated or loaded here (procedural scenes take moments; mesh files are the user's).
    std::map<size_t, std::optional<uint64_t>> triangles;
    size_t skipped = 0;
    std::printf("%-4s %-16s %s\n", "#", "combo_id", "model/accel:given parameters  [status]");
    for (size_t i = 0; i < selected.size(); ++i) {
        const Combination& c = *selected[i];
        if (!triangles.count(c.model)) {
            const ModelSpec& spec = config.models[c.model];
            std::optional<uint64_t> t = known_triangles(spec, registry);
            if (!t && !config.skip.empty()) {
                try {
                    t = load_model(spec, registry, config.render).scene.triangle_count();
                } catch (const std::exception& e) {
                    std::fprintf(stderr, "accelbench run: cannot load %s: %s\n", spec.label.c_str(), e.what());
                }
            }
            triangles[c.model] = t;
        }
        std::string status;
        if (auto t = triangles[c.model]) {
            if (auto reason = skip_reason(config, c, *t)) {
                status = "  [skip: " + *reason + "]";
                ++skipped;
            }
        } else if (!config.skip.empty()) {
            status = "  [triangle count unknown until loaded]";
        }
        if (status.find("skip") == std::string::npos &&
            (repetitions_of(config, c) != config.repetitions || warmup_of(config, c) != config.warmup))
            status += "  [" + std::to_string(repetitions_of(config, c)) + " repetitions, warm-up " +
                      std::to_string(warmup_of(config, c)) + "]";
        std::printf("%-4zu %-16s %s%s\n", i + 1, c.id.c_str(), c.name.c_str(), status.c_str());
    }
    std::printf("%zu combinations", selected.size());
    if (shard && shard->count > 1) std::printf(" in shard %llu/%llu (of %zu in the config)", (unsigned long long)shard->index,
                                               (unsigned long long)shard->count, all.size());
    std::printf(": %zu to measure, %zu skipped by rules; %d repetitions and warm-up %d unless shown, timeout %s s each\n",
                selected.size() - skipped, skipped, config.repetitions, config.warmup, num(config.timeout_s, 6).c_str());
}

int run(const RunOptions& opt) {
    ModelRegistry registry;
    Config config;
    std::vector<Combination> all;
    try {
        registry = ModelRegistry::load_default();
        config = load_config(opt.config_path, registry);
        all = expand(config);
    } catch (const ConfigError& e) {
        for (const auto& issue : e.issues()) std::fprintf(stderr, "%s\n", format_issue(issue).c_str());
        std::fprintf(stderr, "accelbench run: %zu error%s in %s; nothing was run\n", e.issues().size(),
                     e.issues().size() == 1 ? "" : "s", opt.config_path.c_str());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench run: %s\n", e.what());
        return 2;
    }

    std::optional<Shard> shard = opt.shard;
    try {
        if (!shard) shard = shard_from_slurm();
    } catch (const std::invalid_argument& e) {
        return usage_error(e.what());
    }
    std::vector<const Combination*> selected;
    for (const auto& c : all)
        if (!shard || shard->contains(c)) selected.push_back(&c);

    if (opt.dry_run) {
        print_dry_run(config, all, selected, shard, registry);
        return 0;
    }

    // Where the rows go.
    const std::string runs_dir = (fs::path(registry.project_dir()) / "results" / "runs").string();
    std::string out = opt.out;
    if (out.empty() && opt.resume) {
        auto newest = newest_run(runs_dir, config.name, shard_suffix(shard));
        if (!newest) return usage_error("--resume without --out: no earlier run of '" + config.name + "' in " + runs_dir);
        out = *newest;
    }
    if (out.empty()) out = runs_dir + "/" + config.name + "-" + utc_now("%Y%m%d-%H%M%S") + shard_suffix(shard) + ".csv";
    if (!opt.resume && fs::exists(out) && fs::file_size(out) > 0)
        return usage_error("'" + out + "' exists: pass --resume to continue it, or choose another --out");

    std::set<std::string> done;
    std::optional<CsvAppender> results, reps;
    try {
        if (opt.resume) done = prepare_resume(out, result_columns(), repetition_columns());
        results.emplace(out, result_columns());
        reps.emplace(repetitions_path(out), repetition_columns());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench run: %s\n", e.what());
        return 2;
    }
    std::vector<const Combination*> todo;
    for (const Combination* c : selected)
        if (!done.count(c->id)) todo.push_back(c);

    // Google Benchmark's own flags (all but --benchmark_out, which this process owns).
    std::vector<std::string> gb_args = {"accelbench run"};
    gb_args.insert(gb_args.end(), opt.benchmark_args.begin(), opt.benchmark_args.end());
    std::vector<char*> gb_argv;
    for (auto& a : gb_args) gb_argv.push_back(a.data());
    int gb_argc = int(gb_argv.size());
    benchmark::Initialize(&gb_argc, gb_argv.data());
    if (gb_argc > 1) return usage_error(std::string("unknown Google Benchmark flag '") + gb_argv[1] + "'");
    std::optional<JsonOutput> json;
    try {
        if (!opt.json_out.empty()) json.emplace(opt.json_out);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench run: %s\n", e.what());
        return 2;
    }

    std::fprintf(stderr, "accelbench run: %s: %zu combinations%s, %zu already in %s, %zu to go\n", config.name.c_str(),
                 selected.size(), shard && shard->count > 1 ? (" in shard " + std::to_string(shard->index) + "/" +
                                                              std::to_string(shard->count)).c_str() : "",
                 selected.size() - todo.size(), out.c_str(), todo.size());

    const auto t_start = Clock::now();
    double measured_s = 0;
    size_t measured = 0, k = 0;
    std::map<std::string, size_t> by_status;
    bool first_measurement = true;
    std::vector<std::string> unloadable;  // "label: why" of models that did not load
    size_t not_run = 0;                   // their combinations
    VerdictTable verdicts;
    for (size_t mi = 0; mi < config.models.size(); ++mi) {
        std::vector<const Combination*> mine;
        for (const Combination* c : todo)
            if (c->model == mi) mine.push_back(c);
        if (mine.empty()) continue;
        const ModelSpec& spec = config.models[mi];

        // Loaded at most once, and only when something is measured on it (or when its
        // triangle count is needed for a skip rule and the registry does not know it).
        // A model that does not load is bad input: its combinations get no rows at all
        // (nothing that could be taken for a result; --resume runs them once it is
        // fixed) and the run exits with 2.
        std::optional<LoadedModel> loaded;
        std::string load_error, reference_error;
        auto ensure_loaded = [&] {
            if (loaded || !load_error.empty()) return;
            const auto t0 = Clock::now();
            try {
                loaded = load_model(spec, registry, config.render);
                std::fprintf(stderr, "accelbench run: loaded %s: %zu triangles, %zu vertices in %.2f s\n",
                             spec.label.c_str(), loaded->scene.triangle_count(), loaded->scene.vertex_count(),
                             std::chrono::duration<double>(Clock::now() - t0).count());
            } catch (const std::exception& e) {
                load_error = e.what();
                std::fprintf(stderr, "accelbench run: cannot load %s: %s\n", spec.label.c_str(), e.what());
                unloadable.push_back(spec.label + ": " + load_error);
            }
        };
        // The reference's answers, once per model, before its first measurement (not under
        // callgrind, whose instruction counts are the point of such a run).
        auto ensure_reference = [&] {
            if (!config.errors || loaded->robustness_case || !opt.callgrind_out.empty() || loaded->reference ||
                !reference_error.empty())
                return;
            try {
                add_reference_answers(*loaded, config.render);
                std::fprintf(stderr, "accelbench run: reference answers for %s: %zu primary rays in %.2f s\n",
                             spec.label.c_str(), loaded->reference->hits.size(), loaded->reference->seconds);
            } catch (const std::exception& e) {
                reference_error = e.what();
                std::fprintf(stderr, "accelbench run: the reference cannot trace %s: %s\n", spec.label.c_str(),
                             e.what());
            }
        };
        std::optional<uint64_t> triangles = known_triangles(spec, registry), vertices;
        if (const ModelEntry* entry = spec.kind == ModelSpec::Kind::Registry ? registry.find(spec.name) : nullptr)
            vertices = entry->vertices;
        if (!triangles) {
            ensure_loaded();
            if (loaded) triangles = loaded->scene.triangle_count(), vertices = loaded->scene.vertex_count();
        }

        for (const Combination* c : mine) {
            ++k;
            const double elapsed = std::chrono::duration<double>(Clock::now() - t_start).count();
            std::string eta = measured ? ", about " + clock_text(measured_s / double(measured) * double(todo.size() - k + 1)) + " left"
                                       : "";
            std::fprintf(stderr, "[%zu/%zu] %s  (elapsed %s%s)\n", k, todo.size(), c->name.c_str(),
                         clock_text(elapsed).c_str(), eta.c_str());

            Row row = base_row(config, *c, triangles, vertices);
            Measurement m;
            std::optional<std::string> reason;
            if (triangles) reason = skip_reason(config, *c, *triangles);
            if (reason) {
                m.status = "skipped";
                m.message = *reason;
            } else {
                ensure_loaded();
                if (loaded) ensure_reference();
                if (!loaded) {
                    ++not_run;
                    continue;
                } else if (!reference_error.empty()) {
                    m.status = "error";
                    m.message = "no error measurement: the reference cannot trace the model: " + reference_error;
                } else {
                    const AcceleratorInfo* info = find_accelerator(c->accel);
                    MeasureSettings ms;
                    ms.repetitions = repetitions_of(config, *c);
                    ms.warmup = warmup_of(config, *c);
                    ms.show_repetitions = opt.show_repetitions;
                    ms.show_context = first_measurement;
                    ms.json = json.has_value();
                    ms.timeout_s = config.timeout_s;
                    ms.callgrind_out = opt.callgrind_out;
                    ms.callgrind_tag = c->id;
                    if (!opt.callgrind_out.empty()) {
                        // Under valgrind times are not measurements and every render is slow:
                        // one counted repetition (the counted one), the counting render as warm-up.
                        ms.repetitions = 1;
                        ms.warmup = std::min(ms.warmup, 1);
                    }
                    first_measurement = false;
                    auto work = [&](const StageFn& stage) {
                        if (loaded->robustness_case)
                            return judge_measurement(c->accel, c->given, *loaded->robustness_case, stage);
                        return measure(c->name, *info, c->params, *loaded, config.render, ms, stage);
                    };
                    const auto t0 = Clock::now();
                    m = opt.in_process ? work(StageFn{}) : run_isolated(work, config.timeout_s);
                    measured_s += std::chrono::duration<double>(Clock::now() - t0).count();
                    ++measured;
                    if (json) json->add(m.json);
                }
            }
            add_measurement(row, m);
            ++by_status[m.status];
            if (spec.kind == ModelSpec::Kind::Case) verdicts.add(spec.label, *c, m);
            if (m.status != "ok")
                std::fprintf(stderr, "[%zu/%zu] %s: %s%s%s\n", k, todo.size(), c->name.c_str(), m.status.c_str(),
                             m.message.empty() ? "" : ": ", m.message.c_str());
            try {
                for (size_t i = 0; i < m.render_s.size() && m.status == "ok"; ++i)
                    reps->append({{"config", config.name},
                                  {"combo_id", c->id},
                                  {"model", row["model"]},
                                  {"accel", c->accel},
                                  {"params", row["params"]},
                                  {"repetition", std::to_string(i + 1)},
                                  {"build_s", num(m.build_s[i])},
                                  {"render_s", num(m.render_s[i])}});
                results->append(row);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "accelbench run: %s\n", e.what());
                return 2;
            }
        }
    }
    if (!verdicts.empty()) {
        std::fflush(stdout);
        verdicts.print(stdout);
    }
    std::string counts;
    for (const auto& [s, n] : by_status) append_item(counts, ", ", std::to_string(n), " ", s);
    std::fprintf(stderr, "accelbench run: %s: %zu rows written to %s (%s) in %s\n", config.name.c_str(), k - not_run,
                 out.c_str(), counts.empty() ? "nothing to do" : counts.c_str(),
                 clock_text(std::chrono::duration<double>(Clock::now() - t_start).count()).c_str());
    if (!unloadable.empty()) {
        for (const auto& u : unloadable) std::fprintf(stderr, "accelbench run: cannot load %s\n", u.c_str());
        std::fprintf(stderr, "accelbench run: %zu combination%s not run and not written: %zu model%s did not load "
                             "(fix and rerun with --resume)\n", not_run, not_run == 1 ? "" : "s", unloadable.size(),
                     unloadable.size() == 1 ? "" : "s");
        return 2;
    }
    return by_status.count("error") ? 1 : 0;
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
                    return usage_error("only --benchmark_out_format=json is supported (our own CSV is the results file)");
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
        return usage_error("--instructions counts with callgrind: run under valgrind --tool=callgrind "
                           "--instr-atstart=no --callgrind-out-file=" + opt.callgrind_out);
    if (opt.resume && opt.out.empty() && opt.dry_run) return usage_error("--resume and --dry-run do not go together");
    return run(opt);
}

int merge_command(int argc, char** argv) {
    bool allow_mixed = false;
    std::string take;
    std::vector<std::string> files;
    for (int i = 0; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--allow-mixed") allow_mixed = true;
        else if (a == "--take-column" && i + 1 < argc) take = argv[++i];
        else if (a == "-h" || a == "--help") {
            std::printf("usage: accelbench merge [--allow-mixed] OUT.csv IN.csv...\n"
                        "       accelbench merge [--allow-mixed] --take-column COLUMN OUT.csv IN.csv FROM.csv\n"
                        "  joins result files (e.g. shards) and their .reps.csv files; refuses inputs whose\n"
                        "  provenance (git_sha, git_dirty, compiler, build_type, cpu, embree_version, isa) differs\n"
                        "  unless --allow-mixed, and a combination present in two inputs.\n"
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
