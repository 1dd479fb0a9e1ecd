#include "plan/combinations.h"

#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "accelbench/accel/registry.h"
#include "accelbench/base/params.h"
#include "util/text.h"

namespace accelbench {

uint64_t fnv1a64(const std::string& text) {
    uint64_t h = 0xcbf29ce484222325ull;
    for (unsigned char ch : text) {
        h ^= ch;
        h *= 0x100000001b3ull;
    }
    return h;
}

std::string hex16(uint64_t v) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)v);
    return buf;
}

std::string combination_key(const ModelSpec& model, const RenderSettings& r, const std::string& accel,
                            const ParamSet& params) {
    // Ray files replace the camera's rays: the image size and samples do not apply.
    std::string render = model.rays
        ? "rays"
        : std::to_string(r.width) + "x" + std::to_string(r.height) + ";spp=" + std::to_string(r.spp);
    render += std::string(";light=") + (r.light ? "1" : "0") + ";shading=" + (r.shading ? "1" : "0") +
        ";threads=" + std::to_string(r.threads);
    // Named only when not IEEE: every row measured before the setting existed traced in
    // IEEE mode, and keeps its id. A robustness case is judged in IEEE mode whatever it says.
    if (r.fp_mode != FpMode::Ieee && model.kind != ModelSpec::Kind::Case)
        render += ";fp_mode=" + std::string(fp_mode_name(r.fp_mode));
    return model.key + "|" + render + "|" + accel + "|" + params.canonical();
}

RenderSettings render_of(const Config& config, const Combination& c) {
    RenderSettings r = config.render;
    r.threads = c.threads;
    return r;
}

std::string ray_set_key(RaySetKind kind, const RaySetParams& p) {
    // Appended piece by piece: GCC 12's -Wrestrict misreads `"literal" + std::string`.
    std::string k = "ray_set=";
    k.append(ray_set_name(kind));
    switch (kind) {
        case RaySetKind::Primary:
        case RaySetKind::Shadow: return k;
        case RaySetKind::Ao:
            k += ";samples=" + std::to_string(p.ao_samples) + ";distance=" + number_text(p.ao_distance);
            break;
        case RaySetKind::Diffuse: k += ";bounces=" + std::to_string(p.diffuse_bounces); break;
        case RaySetKind::Random: k += ";rays=" + std::to_string(p.random_rays); break;
    }
    return k + ";seed=" + std::to_string(p.seed);
}

namespace {

// `max_depth: auto` names the structure's own scene-dependent default: not a given value.
bool is_scene_dependent_default(const AcceleratorInfo& info, const std::string& name, const std::string& value) {
    for (const auto& s : info.params)
        if (s.name == name) return s.scene_dependent_default && value == s.default_value;
    return false;
}

}  // namespace

std::vector<Combination> expand(const Config& config) {
    std::vector<Combination> out;
    std::vector<ConfigIssue> issues;
    std::map<std::string, std::string> seen;  // key -> where it came from
    for (size_t mi = 0; mi < config.models.size(); ++mi) {
        const ModelSpec& model = config.models[mi];
        for (size_t ai = 0; ai < config.accelerators.size(); ++ai) {
            const AcceleratorSpec& a = config.accelerators[ai];
            const AcceleratorInfo* info = find_accelerator(a.name);
            if (!info) throw std::logic_error("expand: accelerator '" + a.name + "' passed validation but is unknown");
            bool has_threads = false;
            for (const auto& s : info->params) has_threads |= s.name == "threads";
            // Odometer over the axes; the last axis turns fastest.
            std::vector<size_t> pos(a.axes.size(), 0);
            for (;;) {
                Combination c;
                c.model = mi;
                c.accelerator = ai;
                c.accel = a.name;
                std::string shown;
                for (size_t k = 0; k < a.axes.size(); ++k) {
                    const ParamAxis& axis = a.axes[k];
                    for (size_t n = 0; n < axis.names.size(); ++n) {
                        const std::string& name = axis.names[n];
                        const std::string& value = axis.values[pos[k]][n];
                        append_item(shown, ",", name, "=", value);
                        if (!is_scene_dependent_default(*info, name, value)) c.given[name] = value;
                    }
                }
                const bool threads_given = c.given.count("threads") > 0;
                std::vector<std::optional<RaySetKind>> sets = {std::nullopt};
                // A robustness case is judged once on its own rays, not per ray set.
                if (config.ray_sets && model.kind != ModelSpec::Kind::Case)
                    sets.assign(config.ray_sets->sets.begin(), config.ray_sets->sets.end());
                for (int threads : config.thread_counts)
                    for (const auto& set : sets) {
                        Combination t = c;
                        t.threads = threads;
                        t.ray_set = set;
                        if (has_threads && !threads_given) t.given["threads"] = std::to_string(threads);
                        t.params = resolve_params(a.name, info->params, t.given);
                        t.key = combination_key(model, render_of(config, t), a.name, t.params);
                        if (set) t.key.append("|").append(ray_set_key(*set, config.ray_sets->params));
                        t.hash = fnv1a64(t.key);
                        t.id = hex16(t.hash);
                        t.name = model.label + "/" + a.name + (shown.empty() ? "" : ":" + shown);
                        if (config.thread_counts.size() > 1) t.name += "/threads=" + std::to_string(threads);
                        if (set) t.name.append("/").append(ray_set_name(*set));
                        const std::string where = model.key_path + " x " + a.key_path;
                        if (auto [it, fresh] = seen.emplace(t.key, where); !fresh)
                            issues.push_back({a.mark, a.key_path,
                                              "combination " + t.name + " (" + where + ") repeats " + it->second +
                                                  ": every combination must be measured once"});
                        else out.push_back(std::move(t));
                    }

                size_t k = a.axes.size();
                while (k > 0 && ++pos[k - 1] == a.axes[k - 1].values.size()) pos[--k] = 0;
                if (k == 0) break;
            }
        }
    }
    if (!issues.empty()) throw ConfigError(std::move(issues));
    return out;
}

int repetitions_of(const Config& config, const Combination& c) {
    return config.accelerators[c.accelerator].repetitions.value_or(
        config.models[c.model].repetitions.value_or(config.repetitions));
}

int warmup_of(const Config& config, const Combination& c) {
    return config.accelerators[c.accelerator].warmup.value_or(config.models[c.model].warmup.value_or(config.warmup));
}

int processes_of(const Config& config, const Combination& c) {
    return config.accelerators[c.accelerator].processes.value_or(
        config.models[c.model].processes.value_or(config.processes));
}

std::optional<std::string> skip_reason(const Config& config, const Combination& c, uint64_t triangles) {
    for (const SkipRule& r : config.skip) {
        if (r.accel && *r.accel != c.accel) continue;
        if (r.model && *r.model != config.models[c.model].label) continue;
        if (r.triangles_above && !(triangles > *r.triangles_above)) continue;
        if (r.triangles_below && !(triangles < *r.triangles_below)) continue;
        bool params_match = true;
        for (const auto& [k, v] : r.params) {
            bool found = false;
            for (const auto& [name, text] : c.params.items()) found |= name == k && text == v;
            params_match &= found;
        }
        if (!params_match) continue;
        return r.reason;
    }
    return std::nullopt;
}

namespace {

// Counts follow the number rule of configs and parameters: "01/4" was read as shard 1
// and "0x1/4" refused as no integer, where a config names both forms.
uint64_t parse_count(const std::string& text, const std::string& what) {
    if (const std::string why = number_form_problem(text); !why.empty()) throw std::invalid_argument(what + ": " + why);
    if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos || text.size() > 12)
        throw std::invalid_argument(what + ": expected a non-negative integer, got '" + text + "'");
    return std::stoull(text);
}

}  // namespace

Shard parse_shard(const std::string& text) {
    const size_t slash = text.find('/');
    if (slash == std::string::npos) throw std::invalid_argument("--shard expects i/n (e.g. 0/4), got '" + text + "'");
    Shard s{parse_count(text.substr(0, slash), "--shard index"), parse_count(text.substr(slash + 1), "--shard count")};
    if (s.count == 0 || s.index >= s.count)
        throw std::invalid_argument("--shard i/n needs 0 <= i < n, got '" + text + "'");
    return s;
}

std::optional<Shard> shard_from_slurm() {
    const char* id = std::getenv("SLURM_ARRAY_TASK_ID");
    const char* count = std::getenv("SLURM_ARRAY_TASK_COUNT");
    if (!id || !count) return std::nullopt;
    const char* min = std::getenv("SLURM_ARRAY_TASK_MIN");
    const uint64_t first = min ? parse_count(min, "SLURM_ARRAY_TASK_MIN") : 0;
    const uint64_t task = parse_count(id, "SLURM_ARRAY_TASK_ID");
    Shard s{0, parse_count(count, "SLURM_ARRAY_TASK_COUNT")};
    if (s.count == 0 || task < first || task - first >= s.count)
        throw std::invalid_argument("SLURM_ARRAY_TASK_ID=" + std::string(id) + " is not within an array of " + count +
                                    " tasks starting at " + std::to_string(first) + " (array ids must be consecutive)");
    s.index = task - first;
    return s;
}

}  // namespace accelbench
