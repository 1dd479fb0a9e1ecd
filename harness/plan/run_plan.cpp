#include "plan/run_plan.h"

#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <map>
#include <regex>
#include <set>

#include "csv/csv.h"
#include "csv/results.h"
#include "plan/loaded_model.h"
#include "util/sha256.h"
#include "util/text.h"

namespace fs = std::filesystem;

namespace accelbench {

std::string utc_now(const char* format) {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[64];
    std::strftime(buf, sizeof buf, format, &tm);
    return buf;
}

namespace {

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

std::string vec3_text(const Vec3& v) { return number_text(v.x) + "," + number_text(v.y) + "," + number_text(v.z); }

// A registry model is its file (the registry checks it against the checksum when loading)
// seen from its camera under its light.
std::string registry_entry_sha256(const ModelEntry& entry) {
    std::string text = "file " + entry.sha256;
    if (entry.camera)
        text += ";camera " + vec3_text(entry.camera->eye) + " " + vec3_text(entry.camera->look_at) + " " +
            vec3_text(entry.camera->up) + " " + number_text(entry.camera->fov_deg);
    if (entry.light) text += ";light " + vec3_text(entry.light->position);
    return sha256_hex(text);
}

}  // namespace

RunInputs inputs_of(const Config& config, const ModelRegistry& registry) {
    RunInputs inputs = {{"config", sha256_file(config.path), config.name}};
    std::set<std::string> ray_files;
    for (const ModelSpec& m : config.models) {
        if (m.kind == ModelSpec::Kind::Path) inputs.push_back({"model", sha256_file(m.resolved_path), m.label});
        if (m.kind == ModelSpec::Kind::Registry)
            if (const ModelEntry* entry = registry.find(m.name))
                inputs.push_back({"model", registry_entry_sha256(*entry), m.label});
        if (m.rays && ray_files.insert(m.rays->path).second)
            inputs.push_back({"rays", sha256_file(m.rays->path), m.rays->display});
    }
    return inputs;
}

std::string model_file_changed(const RunPlan& plan, const ModelSpec& model) {
    if (model.kind != ModelSpec::Kind::Path) return "";
    const std::string now = sha256_file(model.resolved_path);
    for (const RunInput& i : plan.inputs)
        if (i.kind == "model" && i.name == model.label && i.sha256 != now)
            return model.resolved_path + " changed since the run started (sha256 " + i.sha256.substr(0, 12) +
                " then, " + now.substr(0, 12) + " now): its rows would not be of the file the run records";
    return "";
}

RunPlan plan_run(const RunOptions& options) {
    RunPlan plan;
    plan.registry = ModelRegistry::load_default();
    plan.config = load_config(options.config_path, plan.registry);
    plan.all = expand(plan.config);
    plan.shard = options.shard;
    try {
        if (!plan.shard) plan.shard = shard_from_slurm();
    } catch (const std::invalid_argument& e) {
        throw UsageError(e.what());
    }
    for (const auto& c : plan.all)
        if (!plan.shard || plan.shard->contains(c)) plan.selected.push_back(&c);
    plan.inputs = inputs_of(plan.config, plan.registry);
    return plan;
}

void print_dry_run(const RunPlan& plan) {
    const Config& config = plan.config;
    // Triangle counts decide the skip rules: the registry knows them; other models are
    // generated or loaded here (procedural scenes take moments; mesh files are the user's).
    std::map<size_t, std::optional<uint64_t>> triangles;
    size_t skipped = 0;
    std::printf("%-4s %-16s %s\n", "#", "combo_id", "model/accel:given parameters  [status]");
    for (size_t i = 0; i < plan.selected.size(); ++i) {
        const Combination& c = *plan.selected[i];
        if (!triangles.count(c.model)) {
            const ModelSpec& spec = config.models[c.model];
            std::optional<uint64_t> t = known_triangles(spec, plan.registry);
            if (!t && !config.skip.empty()) {
                try {
                    t = load_model(spec, plan.registry, config.render).scene.triangle_count();
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
    std::printf("%zu combinations", plan.selected.size());
    if (plan.shard && plan.shard->count > 1)
        std::printf(" in shard %llu/%llu (of %zu in the config)", (unsigned long long)plan.shard->index,
                    (unsigned long long)plan.shard->count, plan.all.size());
    std::printf(
        ": %zu to measure, %zu skipped by rules; %d repetitions and warm-up %d unless shown, timeout %s s each\n",
        plan.selected.size() - skipped, skipped, config.repetitions, config.warmup,
        number_text(config.timeout_s, 6).c_str());
    // The inputs, as the record beside a results file holds them (a driver compares them
    // before continuing a run).
    std::printf("inputs (compared by --resume and merge):\n");
    for (const RunInput& i : plan.inputs)
        std::printf("  %-6s %s %s\n", i.kind.c_str(), i.sha256.c_str(), i.name.c_str());
}

void choose_output(RunPlan& plan, const RunOptions& options) {
    const std::string runs_dir = (fs::path(plan.registry.project_dir()) / "results" / "runs").string();
    plan.out = options.out;
    if (plan.out.empty() && options.resume) {
        auto newest = newest_run(runs_dir, plan.config.name, shard_suffix(plan.shard));
        if (!newest)
            throw UsageError("--resume without --out: no earlier run of '" + plan.config.name + "' in " + runs_dir);
        plan.out = *newest;
    }
    if (plan.out.empty())
        plan.out =
            runs_dir + "/" + plan.config.name + "-" + utc_now("%Y%m%d-%H%M%S") + shard_suffix(plan.shard) + ".csv";
    const std::string reps = repetitions_path(plan.out);
    require_regular_file_or_absent(plan.out, "--out (the results CSV)");
    require_regular_file_or_absent(reps, "the repetitions file beside --out");
    const auto has_rows = [](const std::string& p) { return fs::exists(p) && fs::file_size(p) > 0; };
    if (!options.resume && has_rows(plan.out))
        throw UsageError("'" + plan.out + "' exists: pass --resume to continue it, or choose another --out");
    // Repetitions without their results file (deleted, or another run's): a new run would
    // append its samples to them. Refused; --resume drops them (they have no results rows).
    if (!options.resume && has_rows(reps))
        throw UsageError(
            "'" + reps + "' exists without results in '" + plan.out +
            "': its samples are another run's; "
            "remove it, pass --resume (which drops repetitions without a results row), or choose another --out");
    plan.lock = OutputLock({plan.out, reps});
    // Rows measured from other inputs would mix; a file of a header only holds none.
    if (options.resume && has_rows(plan.out) && !read_csv(plan.out).rows.empty()) {
        const auto recorded = read_inputs(plan.out);
        if (!recorded)
            throw std::runtime_error("'" + plan.out +
                                     "' has rows but no record of the inputs they were measured from (" +
                                     inputs_path(plan.out) +
                                     "; written by an older build?): continuing it could mix rows of other "
                                     "contents; choose another --out");
        if (const std::string d = inputs_differences(*recorded, "its rows", plan.inputs, options.config_path);
            !d.empty())
            throw std::runtime_error("'" + plan.out + "' was measured from other inputs than " + options.config_path +
                                     " has now (" + d +
                                     "): continuing it would mix rows of different contents under the same "
                                     "names; choose another --out");
    }
    if (options.resume) plan.done = prepare_resume(plan.out, result_columns(), repetition_columns());
    write_inputs(plan.out, plan.inputs);
    for (const Combination* c : plan.selected)
        if (!plan.done.count(c->id)) plan.to_do.push_back(c);
}

}  // namespace accelbench
