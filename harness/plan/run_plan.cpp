#include "plan/run_plan.h"

#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <map>
#include <regex>
#include <set>

#include "accelbench/scene/mesh_io.h"
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
        if (m.kind == ModelSpec::Kind::Path) {
            inputs.push_back({"model", sha256_file(m.resolved_path), m.label});
            // A file another library reads says which (and its version) in the record of
            // its rows' inputs; our own readers are the code's, which git_sha records.
            if (const std::string reader = mesh_reader(m.resolved_path); reader != "accelbench")
                inputs.push_back({"reader", sha256_hex(reader), m.label + " read by " + reader});
        }
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

namespace {

// One selected combination as the dry run shows it: the model's triangle count when known
// (or cheaply found) and, with it, the skip rule that matches.
struct DryRunRow {
    const Combination* combination;
    std::optional<uint64_t> triangles;
    std::optional<std::string> skip;
};

// Triangle counts decide the skip rules: the registry knows them; other models are
// generated or loaded here (procedural scenes take moments; mesh files are the user's).
std::vector<DryRunRow> dry_run_rows(const RunPlan& plan) {
    const Config& config = plan.config;
    std::map<size_t, std::optional<uint64_t>> triangles;
    std::vector<DryRunRow> rows;
    for (const Combination* c : plan.selected) {
        if (!triangles.count(c->model)) {
            const ModelSpec& spec = config.models[c->model];
            std::optional<uint64_t> t = known_triangles(spec, plan.registry);
            if (!t && !config.skip.empty()) {
                try {
                    t = load_model(spec, plan.registry, config.render).scene.triangle_count();
                } catch (const std::exception& e) {
                    std::fprintf(stderr, "accelbench run: cannot load %s: %s\n", spec.label.c_str(), e.what());
                }
            }
            triangles[c->model] = t;
        }
        const std::optional<uint64_t> t = triangles[c->model];
        rows.push_back({c, t, t ? skip_reason(config, *c, *t) : std::nullopt});
    }
    return rows;
}

void print_dry_run_text(const RunPlan& plan, const std::vector<DryRunRow>& rows) {
    const Config& config = plan.config;
    size_t skipped = 0;
    std::printf("%-4s %-16s %s\n", "#", "combo_id", "model/accel:given parameters  [status]");
    for (size_t i = 0; i < rows.size(); ++i) {
        const Combination& c = *rows[i].combination;
        std::string status;
        if (rows[i].skip) {
            status = "  [skip: " + *rows[i].skip + "]";
            ++skipped;
        } else if (!rows[i].triangles && !config.skip.empty()) {
            status = "  [triangle count unknown until loaded]";
        }
        if (!rows[i].skip && (repetitions_of(config, c) != config.repetitions || warmup_of(config, c) != config.warmup))
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

std::string json_list(const std::vector<std::string>& items) {
    std::string s = "[";
    for (size_t i = 0; i < items.size(); ++i) s.append(i ? ", " : "").append(items[i]);
    return s + "]";
}

std::string json_strings(const std::vector<std::string>& texts) {
    std::vector<std::string> quoted;
    for (const std::string& t : texts) quoted.push_back(json_quoted(t));
    return json_list(quoted);
}

std::string json_accelerator(const AcceleratorSpec& a) {
    std::vector<std::string> axes;
    for (const ParamAxis& axis : a.axes) {
        std::vector<std::string> tuples;
        for (const auto& tuple : axis.values) tuples.push_back(json_strings(tuple));
        axes.push_back("{\"names\": " + json_strings(axis.names) + ", \"values\": " + json_list(tuples) + "}");
    }
    return "{\"entry\": " + json_quoted(a.key_path) + ", \"name\": " + json_quoted(a.name) +
        ", \"axes\": " + json_list(axes) + "}";
}

std::string json_combination(const Config& config, const DryRunRow& row) {
    const Combination& c = *row.combination;
    std::vector<std::string> given;
    for (const auto& [name, value] : c.given) given.push_back(json_quoted(name) + ": " + json_quoted(value));
    std::string s = "{\"combo_id\": " + json_quoted(c.id) +
        ", \"model\": " + json_quoted(config.models[c.model].label) + ", \"accel\": " + json_quoted(c.accel) +
        ", \"entry\": " + json_quoted(config.accelerators[c.accelerator].key_path) + ", \"given\": {";
    for (size_t i = 0; i < given.size(); ++i) s.append(i ? ", " : "").append(given[i]);
    s += "}, \"params\": " + json_quoted(c.params.canonical()) + ", \"threads\": " + std::to_string(c.threads);
    s += ", \"ray_set\": " + (c.ray_set ? json_quoted(std::string(ray_set_name(*c.ray_set))) : std::string("null"));
    s += ", \"triangles\": " + (row.triangles ? std::to_string(*row.triangles) : std::string("null"));
    s += ", \"skip\": " + (row.skip ? json_quoted(*row.skip) : std::string("null"));
    s += ", \"repetitions\": " + std::to_string(repetitions_of(config, c)) +
        ", \"warmup\": " + std::to_string(warmup_of(config, c)) +
        ", \"processes\": " + std::to_string(processes_of(config, c)) + "}";
    return s;
}

// The expansion for programs (the analysis's grid search reads its axes here instead of
// expanding ranges itself): the config's models and accelerator entries with their axes as
// canonical values, then every selected combination.
void print_dry_run_json(const RunPlan& plan, const std::vector<DryRunRow>& rows) {
    const Config& config = plan.config;
    std::vector<std::string> models, accelerators, combinations;
    for (const ModelSpec& m : config.models) models.push_back(json_quoted(m.label));
    for (const AcceleratorSpec& a : config.accelerators) accelerators.push_back(json_accelerator(a));
    for (const DryRunRow& row : rows) combinations.push_back(json_combination(config, row));
    const auto lines = [](const std::vector<std::string>& items) {
        std::string s = "[";
        for (size_t i = 0; i < items.size(); ++i) s.append(i ? ",\n    " : "\n    ").append(items[i]);
        return s + (items.empty() ? "]" : "\n  ]");
    };
    const std::string shard =
        plan.shard ? json_quoted(std::to_string(plan.shard->index) + "/" + std::to_string(plan.shard->count)) : "null";
    std::printf("{\n  \"config\": %s,\n  \"combinations_in_config\": %zu,\n  \"shard\": %s,\n",
                json_quoted(config.name).c_str(), plan.all.size(), shard.c_str());
    std::printf("  \"models\": %s,\n  \"accelerators\": %s,\n  \"combinations\": %s\n}\n", lines(models).c_str(),
                lines(accelerators).c_str(), lines(combinations).c_str());
}

}  // namespace

void print_dry_run(const RunPlan& plan, bool json) {
    const std::vector<DryRunRow> rows = dry_run_rows(plan);
    if (json) print_dry_run_json(plan, rows);
    else print_dry_run_text(plan, rows);
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
    require_results_name(plan.out);
    const std::string reps = repetitions_path(plan.out);
    require_regular_file_or_absent(plan.out, "--out (the results CSV)");
    require_regular_file_or_absent(reps, "the repetitions file beside --out");
    require_inputs_path_free(plan.out);
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
        // Rows of another build (or machine) would mix with this one's in every median.
        if (!options.allow_mixed) check_same_build({read_csv(plan.out), this_build_rows()}, {plan.out, "this build"});
    }
    if (options.resume) plan.done = prepare_resume(plan.out, result_columns(), repetition_columns());
    write_inputs(plan.out, plan.inputs);
    for (const Combination* c : plan.selected)
        if (!plan.done.count(c->id)) plan.to_do.push_back(c);
}

}  // namespace accelbench
