// Reading a config: the document's top level and the run's own settings (name,
// description, repetitions, warmup, processes, timeout_s, errors) here, each other group of keys in
// its section file (config_sections.h), then the limits that need the whole config.
#include "config/config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>

#include "accelbench/accel/registry.h"
#include "config/config_sections.h"

namespace fs = std::filesystem;

namespace accelbench {

std::string ModelTransformSpec::text() const {
    return std::string(kind == Kind::Decimate ? "decimate=" : "subdivide=") + std::to_string(amount);
}

ConfigReader::ConfigReader(const std::string& path, const ModelRegistry& models) : registry(models) {
    c.file = path;
    cfg.path = path;
    fs::path dir = fs::path(path).parent_path();
    cfg.dir = dir.empty() ? "." : dir.string();
}

std::string ConfigReader::resolve(const std::string& p) const {
    fs::path fp(p);
    return (fp.is_absolute() ? fp : fs::path(cfg.dir) / fp).lexically_normal().string();
}

// `repetitions`, `warmup` and `processes` of a model or an accelerator entry (for the slow
// ones).
bool read_effort(ConfigReader& r, const Fields& f, std::optional<int>& repetitions, std::optional<int>& warmup,
                 std::optional<int>& processes) {
    bool ok = true;
    if (auto* e = f.find("repetitions")) {
        if (auto v = read_int(r.c, e->value, f.child("repetitions"), 1, 1000)) repetitions = int(*v);
        else ok = false;
    }
    if (auto* e = f.find("warmup")) {
        if (auto v = read_int(r.c, e->value, f.child("warmup"), 0, 100)) warmup = int(*v);
        else ok = false;
    }
    if (auto* e = f.find("processes")) {
        if (auto v = read_int(r.c, e->value, f.child("processes"), 1, 10)) processes = int(*v);
        else ok = false;
    }
    return ok;
}

namespace {

// name, description, repetitions, warmup, processes, timeout_s, errors.
void read_run_settings(ConfigReader& r, const Fields& top) {
    r.cfg.name = fs::path(r.cfg.path).stem().string();
    if (auto* e = top.find("name"))
        if (auto s = read_string(r.c, e->value, "name")) {
            if (s->find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-") !=
                std::string::npos)
                r.c.error(e->value, "name", "'" + *s + "' is used in file names: use letters, digits, '.', '_', '-'");
            else r.cfg.name = *s;
        }
    if (auto* e = top.find("description")) read_string(r.c, e->value, "description");
    if (auto* e = top.find("repetitions"))
        if (auto v = read_int(r.c, e->value, "repetitions", 1, 1000)) r.cfg.repetitions = int(*v);
    if (auto* e = top.find("warmup"))
        if (auto v = read_int(r.c, e->value, "warmup", 0, 100)) r.cfg.warmup = int(*v);
    if (auto* e = top.find("processes"))
        if (auto v = read_int(r.c, e->value, "processes", 1, 10)) r.cfg.processes = int(*v);
    if (auto* e = top.find("timeout_s"))
        if (auto v = read_number(r.c, e->value, "timeout_s", 0, 1e7, true)) r.cfg.timeout_s = *v;
    if (auto* e = top.find("errors"))
        if (auto v = read_bool(r.c, e->value, "errors")) r.cfg.errors = *v;
    if (auto* e = top.find("interleave"))
        if (auto v = read_bool(r.c, e->value, "interleave")) r.cfg.interleave = *v;
}

// The number of combinations (models x the sum over accelerator entries of the product
// of their axes x thread counts x ray sets) is bounded before anything is expanded: three ranges of 10,000 values
// each would otherwise allocate 10^12 combinations, with --dry-run too.
void check_combination_count(ConfigReader& r, const Fields& top) {
    uint64_t per_model = 0;
    bool over = false;
    for (const auto& a : r.cfg.accelerators) {
        uint64_t product = 1;
        for (const auto& axis : a.axes) over |= __builtin_mul_overflow(product, uint64_t(axis.values.size()), &product);
        over |= __builtin_add_overflow(per_model, product, &per_model);
    }
    // Every model, thread count and ray set is a combination of each setting.
    const uint64_t sets = r.cfg.ray_sets ? std::max<uint64_t>(1, r.cfg.ray_sets->sets.size()) : 1;
    const uint64_t threads = std::max<uint64_t>(1, r.cfg.thread_counts.size());
    uint64_t total = 0;
    over |= __builtin_mul_overflow(per_model, uint64_t(r.cfg.models.size()), &total);
    over |= __builtin_mul_overflow(total, threads, &total);
    over |= __builtin_mul_overflow(total, sets, &total);
    if (over || total > kMaxCombinations) {
        const auto* e = top.find("accelerators");
        r.c.error(e ? e->value : top.node(), "accelerators",
                  "the config expands to " + (over ? std::string("more than 2^64") : std::to_string(total)) +
                      " combinations (" + std::to_string(r.cfg.models.size()) +
                      (r.cfg.models.size() == 1 ? " model x " : " models x ") +
                      (over ? std::string("too many") : std::to_string(per_model)) + " accelerator settings x " +
                      std::to_string(threads) + (threads == 1 ? " thread count x " : " thread counts x ") +
                      std::to_string(sets) + (sets == 1 ? " ray set" : " ray sets") + "); at most " +
                      std::to_string(kMaxCombinations) +
                      " in one config: split it, or use grid.mode: successive_halving");
    }
}

// With error columns, the reference keeps every primary ray's hit, and so does the
// measurement's second counting render (16 bytes each, plus the images in an image
// run): an image that cannot fit is refused here, not as std::bad_alloc in a row.
void check_reference_size(ConfigReader& r) {
    if (!r.cfg.errors) return;
    const RenderSettings& render = r.cfg.render;
    const uint64_t camera_rays = uint64_t(render.width) * uint64_t(render.height) * uint64_t(render.spp);
    uint64_t most = 0;
    const ModelSpec* worst = nullptr;
    for (const auto& m : r.cfg.models) {
        if (m.kind == ModelSpec::Kind::Case) continue;  // its own small ray set
        const uint64_t rays = m.rays ? uint64_t(m.rays->rays.size()) : camera_rays;
        if (rays > most) most = rays, worst = &m;
    }
    if (most <= kMaxReferenceRays) return;
    const std::string what = worst->rays
        ? "the ray file " + worst->rays->display + " has " + std::to_string(most) + " rays"
        : "render: width x height x spp = " + std::to_string(most) + " primary rays";
    r.c.issues.push_back({worst->mark, worst->key_path,
                          what +
                              "; with error columns the reference keeps a 16-byte hit per primary ray (twice, "
                              "with the measurement's), at most " +
                              std::to_string(kMaxReferenceRays) + " rays: a smaller image or spp, or errors: false"});
}

}  // namespace

Config load_config(const std::string& path, const ModelRegistry& models) {
    ConfigReader r(path, models);
    const YAML::Node root = load_yaml_document(path);
    // `grid:` belongs to the analysis's grid search (analysis/README.md): accepted, unread.
    Fields top(r.c, root, "",
               {"name", "description", "repetitions", "warmup", "processes", "interleave", "timeout_s", "errors",
                "render", "ray_sets", "rays", "models", "accelerators", "skip", "grid", "plugins"});
    if (!top.ok()) throw ConfigError(r.c.issues);
    // Before `accelerators`, which may name the plugins' structures.
    if (auto* e = top.find("plugins")) read_plugins(r, e->value);
    read_run_settings(r, top);
    r.cfg.render.shading = false;  // timing measures tracing; shading costs every structure the same
    if (auto* e = top.find("render")) read_render(r, e->value);
    if (auto* e = top.find("rays")) r.default_rays = read_rays(r, e->value, "rays");
    if (auto* e = top.find("ray_sets")) read_ray_sets(r, e->value);
    if (auto* e = top.require("models")) read_models(r, e->value);
    if (auto* e = top.require("accelerators")) read_accelerators(r, e->value);
    check_combination_count(r, top);
    check_reference_size(r);
    if (auto* e = top.find("skip")) read_skip_rules(r, e->value);
    if (!r.c.issues.empty()) throw ConfigError(r.c.issues);
    return std::move(r.cfg);
}

}  // namespace accelbench
