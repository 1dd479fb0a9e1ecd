// `render:`, `ray_sets:` and the top-level `rays:`: what is traced, the image and its
// threads, the ray sets beside the camera rows, and the ray files.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <thread>

#include "accelbench/base/param_table.h"
#include "accelbench/base/unknown_name.h"
#include "config/config_sections.h"
#include "config/ray_file.h"
#include "util/text.h"

namespace fs = std::filesystem;

namespace accelbench {

namespace {

// One count, a list of counts, or "1..nproc" (every count from 1 to the machine's
// hardware threads): render.threads is the first.
void read_threads(ConfigReader& r, const YAML::Node& n, const std::string& path) {
    std::vector<int> counts;
    if (n.IsScalar() && n.Scalar() == "1..nproc") {
        const int nproc = int(std::max(1u, std::thread::hardware_concurrency()));
        for (int t = 1; t <= nproc; ++t) counts.push_back(t);
    } else if (n.IsSequence()) {
        read_list(r.c, n, path, [&](const YAML::Node& item, const std::string& p) {
            if (auto v = read_int(r.c, item, p, 1, kMaxThreads)) {
                if (std::find(counts.begin(), counts.end(), int(*v)) != counts.end())
                    r.c.error(item, p, "thread count " + std::to_string(*v) + " is listed twice");
                else counts.push_back(int(*v));
            }
        });
    } else if (auto v = read_int(r.c, n, path, 1, kMaxThreads)) {
        counts.push_back(int(*v));
    }
    if (counts.empty()) return;
    r.cfg.thread_counts = counts;
    r.cfg.render.threads = counts.front();
}

// Each set's rays and the reference's answers for them (and the measurement's second
// counting trace) are held in memory, every set of a model at once: a set larger than
// kMaxRaySetBytes, or sets that are larger together, are refused here, naming the keys
// that make them, before any set is made (not as std::bad_alloc in a model's loading).
void check_ray_set_bytes(ConfigReader& r, const RaySetsSpec& spec, const Fields& f, const YAML::Node& n) {
    const RenderSettings& render = r.cfg.render;
    const uint64_t primary = uint64_t(render.width) * uint64_t(render.height) * uint64_t(render.spp);
    const auto node_of = [&](const char* group, const char* key) -> std::pair<YAML::Node, std::string> {
        if (auto* e = f.find(group))
            if (e->value.IsMap() && e->value[key]) return {e->value[key], f.child(group) + "." + key};
        return {n, "ray_sets"};
    };
    uint64_t total = 0;
    std::string shares;  // "name N bytes, ..." of every set
    bool each_fits = true;
    for (RaySetKind kind : spec.sets) {
        uint64_t rays = primary;
        std::string why = "render: width x height x spp = " + std::to_string(primary) + " primary rays";
        std::pair<YAML::Node, std::string> at = {n, "ray_sets"};
        if (kind == RaySetKind::Ao) {
            rays = primary * uint64_t(spec.params.ao_samples);
            at = node_of("ao", "samples");
            why = "ray_sets.ao.samples x width x height x spp = " + std::to_string(spec.params.ao_samples) + " x " +
                std::to_string(primary) + " = " + std::to_string(rays) + " rays";
        } else if (kind == RaySetKind::Diffuse) {
            rays = primary * uint64_t(spec.params.diffuse_bounces);
            at = node_of("diffuse", "bounces");
            why = "ray_sets.diffuse.bounces x width x height x spp = " + std::to_string(spec.params.diffuse_bounces) +
                " x " + std::to_string(primary) + " = " + std::to_string(rays) + " rays";
        } else if (kind == RaySetKind::Random) {
            rays = spec.params.random_rays;
            at = node_of("random", "rays");
            why = "ray_sets.random.rays = " + std::to_string(rays) + " rays";
        }
        const uint64_t bytes = rays * kRaySetBytesPerRay;
        total += bytes;
        append_item(shares, ", ", ray_set_name(kind), " ", std::to_string(bytes));
        if (bytes <= kMaxRaySetBytes) continue;
        each_fits = false;
        r.c.error(at.first, at.second,
                  "ray set '" + std::string(ray_set_name(kind)) + "': " + why + ", " + std::to_string(bytes) +
                      " bytes with their answers (" + std::to_string(kRaySetBytesPerRay) + " a ray); at most " +
                      std::to_string(kMaxRaySetBytes) + " bytes (" +
                      std::to_string(kMaxRaySetBytes / kRaySetBytesPerRay) + " rays) a set");
    }
    if (each_fits && total > kMaxRaySetsTotalBytes)
        r.c.error(n, "ray_sets",
                  "the ray sets together hold " + std::to_string(total) + " bytes with their answers (" + shares +
                      "), all in memory at once; at most " + std::to_string(kMaxRaySetsTotalBytes) +
                      " bytes for every set of a model: fewer sets, or fewer rays (render size, ao.samples, "
                      "diffuse.bounces, random.rays)");
}

}  // namespace

void read_render(ConfigReader& r, const YAML::Node& n) {
    Fields f(r.c, n, "render", {"width", "height", "spp", "light", "shading", "threads", "fp_mode"});
    RenderSettings& render = r.cfg.render;
    if (auto* e = f.find("width"))
        if (auto v = read_int(r.c, e->value, f.child("width"), 1, 16384)) render.width = int(*v);
    if (auto* e = f.find("height"))
        if (auto v = read_int(r.c, e->value, f.child("height"), 1, 16384)) render.height = int(*v);
    if (auto* e = f.find("spp"))
        if (auto v = read_int(r.c, e->value, f.child("spp"), 1, 4096)) render.spp = int(*v);
    if (auto* e = f.find("threads")) read_threads(r, e->value, f.child("threads"));
    if (auto* e = f.find("light"))
        if (auto v = read_bool(r.c, e->value, f.child("light"))) render.light = *v;
    if (auto* e = f.find("shading"))
        if (auto v = read_bool(r.c, e->value, f.child("shading"))) render.shading = *v;
    if (auto* e = f.find("fp_mode"))
        if (auto name = read_string(r.c, e->value, f.child("fp_mode"))) {
            const std::vector<std::string> names(fp_mode_names().begin(), fp_mode_names().end());
            if (auto mode = parse_fp_mode(*name)) render.fp_mode = *mode;
            else
                r.c.error(e->value, f.child("fp_mode"),
                          unknown_name("fp_mode", *name, names, did_you_mean(*name, names)));
        }
}

void read_ray_sets(ConfigReader& r, const YAML::Node& n) {
    Fields f(r.c, n, "ray_sets", {"sets", "ao", "diffuse", "random", "seed"});
    if (!f.ok()) return;
    RaySetsSpec spec;
    if (auto* e = f.find("sets")) {
        read_list(r.c, e->value, f.child("sets"), [&](const YAML::Node& item, const std::string& p) {
            const auto name = read_string(r.c, item, p);
            if (!name) return;
            const auto kind = parse_ray_set(*name);
            std::vector<std::string> names(ray_set_names().begin(), ray_set_names().end());
            if (!kind) r.c.error(item, p, unknown_name("ray set", *name, names, did_you_mean(*name, names)));
            else if (std::find(spec.sets.begin(), spec.sets.end(), *kind) != spec.sets.end())
                r.c.error(item, p, "ray set '" + *name + "' is listed twice");
            else spec.sets.push_back(*kind);
        });
    } else {
        for (auto name : ray_set_names()) spec.sets.push_back(*parse_ray_set(name));
    }
    RaySetParams& p = spec.params;
    if (auto* e = f.find("ao")) {
        Fields ao(r.c, e->value, f.child("ao"), {"samples", "distance"});
        if (auto* s = ao.find("samples"))
            if (auto v = read_int(r.c, s->value, ao.child("samples"), 1, 1024)) p.ao_samples = int(*v);
        if (auto* s = ao.find("distance"))
            if (auto v = read_float(r.c, s->value, ao.child("distance"), 0, 1e3, true)) p.ao_distance = *v;
    }
    if (auto* e = f.find("diffuse")) {
        Fields d(r.c, e->value, f.child("diffuse"), {"bounces"});
        if (auto* s = d.find("bounces"))
            if (auto v = read_int(r.c, s->value, d.child("bounces"), 1, 64)) p.diffuse_bounces = int(*v);
    }
    if (auto* e = f.find("random")) {
        Fields d(r.c, e->value, f.child("random"), {"rays"});
        if (auto* s = d.find("rays"))
            if (auto v = read_int(r.c, s->value, d.child("rays"), 1, int64_t(1) << 30)) p.random_rays = uint64_t(*v);
    }
    if (auto* e = f.find("seed"))
        if (auto v = read_int(r.c, e->value, f.child("seed"), 0, std::numeric_limits<int64_t>::max()))
            p.seed = uint64_t(*v);
    check_ray_set_bytes(r, spec, f, n);
    r.cfg.ray_sets = std::move(spec);
}

std::shared_ptr<const RaySet> read_rays(ConfigReader& r, const YAML::Node& n, const std::string& path) {
    Fields f(r.c, n, path, {"file"});
    auto* e = f.require("file");
    if (!e) return nullptr;
    auto file = read_string(r.c, e->value, f.child("file"));
    if (!file) return nullptr;
    const std::string resolved = r.resolve(*file);
    if (auto it = r.ray_files.find(resolved); it != r.ray_files.end()) return it->second;
    if (!fs::is_regular_file(resolved)) {
        r.c.error(e->value, f.child("file"), "no such ray file: " + resolved);
        return nullptr;
    }
    RayFileContents contents = read_ray_file(resolved, resolved);
    if (!contents.issues.empty()) {
        for (auto& issue : contents.issues) {
            issue.key_path = f.child("file");
            r.c.issues.push_back(std::move(issue));
        }
        return nullptr;
    }
    auto set = std::make_shared<RaySet>(
        RaySet{resolved, fs::path(*file).lexically_normal().string(), std::move(contents.rays)});
    r.ray_files.emplace(resolved, set);
    return set;
}

}  // namespace accelbench
