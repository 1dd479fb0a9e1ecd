#include "config/config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <set>
#include <thread>

#include "accelbench/accel/registry.h"
#include "accelbench/base/params.h"
#include "accelbench/base/unknown_name.h"
#include "accelbench/scene/procedural.h"
#include "accelbench/verify/robustness_cases.h"
#include "config/checked_yaml.h"
#include "config/ray_file.h"
#include "models/model_registry.h"
#include "util/text.h"

namespace fs = std::filesystem;

namespace accelbench {

std::string ModelTransformSpec::text() const {
    return std::string(kind == Kind::Decimate ? "decimate=" : "subdivide=") + std::to_string(amount);
}

namespace {

// parse_param's messages start with "accelerator 'x', parameter 'y': "; the key path
// already says that.
std::string strip_param_prefix(const std::string& msg) {
    const std::string marker = "', parameter '";
    size_t at = msg.find(marker);
    if (at == std::string::npos) return msg;
    size_t end = msg.find("': ", at + marker.size());
    return end == std::string::npos ? msg : msg.substr(end + 3);
}

// One parameter value, validated against its declaration; returns its canonical text
// (so that 1.0 and 1 for a float name the same combination).
std::optional<std::string> read_param_value(Checker& c, const YAML::Node& n, const std::string& path,
                                            const std::string& owner, const ParamSpec& spec) {
    if (!n.IsScalar()) {
        c.error(n, path, std::string("expected a ") + to_string(spec.type) + " value, got " + kind_of(n));
        return std::nullopt;
    }
    if (quoted(n) && spec.type != ParamType::Enum) {
        c.error(
            n, path,
            std::string("expected a ") + to_string(spec.type) + " value, got the quoted string '" + n.Scalar() + "'");
        return std::nullopt;
    }
    // A default that depends on the scene (the kd-tree's max_depth "auto") can be named, so
    // a zipped group can pair it with other values; it means "not given".
    if (spec.scene_dependent_default && n.Scalar() == spec.default_value) return spec.default_value;
    try {
        return format_param(parse_param(owner, spec, n.Scalar()));
    } catch (const ParamError& e) {
        c.error(n, path, strip_param_prefix(e.what()));
        return std::nullopt;
    }
}

const ParamSpec* find_spec(const std::vector<ParamSpec>& specs, const std::string& name) {
    for (const auto& s : specs)
        if (s.name == name) return &s;
    return nullptr;
}

std::vector<std::string> spec_names(const std::vector<ParamSpec>& specs) {
    std::vector<std::string> names;
    for (const auto& s : specs) names.push_back(s.name);
    return names;
}

std::string format_float(double v) { return format_param(ParamValue(v)); }

// ---- the loader ----------------------------------------------------------------------

class Loader {
public:
    Loader(const std::string& path, const ModelRegistry& registry) : registry_(registry) {
        c_.file = path;
        cfg_.path = path;
        fs::path dir = fs::path(path).parent_path();
        cfg_.dir = dir.empty() ? "." : dir.string();
    }

    Config load() {
        const YAML::Node root = load_yaml_document(cfg_.path);

        // `grid:` belongs to the analysis's grid search (analysis/README.md): accepted, unread.
        Fields top(c_, root, "",
                   {"name", "description", "repetitions", "warmup", "timeout_s", "errors", "render", "ray_sets", "rays",
                    "models", "accelerators", "skip", "grid"});
        if (!top.ok()) throw ConfigError(c_.issues);

        cfg_.name = fs::path(cfg_.path).stem().string();
        if (auto* e = top.find("name"))
            if (auto s = read_string(c_, e->value, "name")) {
                if (s->find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-") !=
                    std::string::npos)
                    c_.error(e->value, "name",
                             "'" + *s + "' is used in file names: use letters, digits, '.', '_', '-'");
                else cfg_.name = *s;
            }
        if (auto* e = top.find("description")) read_string(c_, e->value, "description");
        if (auto* e = top.find("repetitions"))
            if (auto v = read_int(c_, e->value, "repetitions", 1, 1000)) cfg_.repetitions = int(*v);
        if (auto* e = top.find("warmup"))
            if (auto v = read_int(c_, e->value, "warmup", 0, 100)) cfg_.warmup = int(*v);
        if (auto* e = top.find("timeout_s"))
            if (auto v = read_number(c_, e->value, "timeout_s", 0, 1e7, true)) cfg_.timeout_s = *v;
        if (auto* e = top.find("errors"))
            if (auto v = read_bool(c_, e->value, "errors")) cfg_.errors = *v;
        cfg_.render.shading = false;  // timing measures tracing; shading costs every structure the same
        if (auto* e = top.find("render")) read_render(e->value);
        if (auto* e = top.find("rays")) default_rays_ = read_rays(e->value, "rays");
        if (auto* e = top.find("ray_sets")) read_ray_sets(e->value);

        if (auto* e = top.require("models"))
            read_list(c_, e->value, "models", [&](const YAML::Node& n, const std::string& p) { read_model(n, p); });
        check_models();
        if (auto* e = top.require("accelerators"))
            read_list(c_, e->value, "accelerators",
                      [&](const YAML::Node& n, const std::string& p) { read_accelerator(n, p); });
        check_thread_counts();
        check_combination_count(top);
        check_reference_size();
        if (auto* e = top.find("skip"))
            read_list(
                c_, e->value, "skip", [&](const YAML::Node& n, const std::string& p) { read_skip(n, p); }, true);

        if (!c_.issues.empty()) throw ConfigError(c_.issues);
        return std::move(cfg_);
    }

private:
    std::string resolve(const std::string& p) const {
        fs::path fp(p);
        return (fp.is_absolute() ? fp : fs::path(cfg_.dir) / fp).lexically_normal().string();
    }

    void read_render(const YAML::Node& n) {
        Fields f(c_, n, "render", {"width", "height", "spp", "light", "shading", "threads"});
        RenderSettings& r = cfg_.render;
        if (auto* e = f.find("width"))
            if (auto v = read_int(c_, e->value, f.child("width"), 1, 16384)) r.width = int(*v);
        if (auto* e = f.find("height"))
            if (auto v = read_int(c_, e->value, f.child("height"), 1, 16384)) r.height = int(*v);
        if (auto* e = f.find("spp"))
            if (auto v = read_int(c_, e->value, f.child("spp"), 1, 4096)) r.spp = int(*v);
        if (auto* e = f.find("threads")) read_threads(e->value, f.child("threads"));
        if (auto* e = f.find("light"))
            if (auto v = read_bool(c_, e->value, f.child("light"))) r.light = *v;
        if (auto* e = f.find("shading"))
            if (auto v = read_bool(c_, e->value, f.child("shading"))) r.shading = *v;
    }

    // One count, a list of counts, or "1..nproc" (every count from 1 to the machine's
    // hardware threads): render.threads is the first.
    void read_threads(const YAML::Node& n, const std::string& path) {
        std::vector<int> counts;
        if (n.IsScalar() && n.Scalar() == "1..nproc") {
            const int nproc = int(std::max(1u, std::thread::hardware_concurrency()));
            for (int t = 1; t <= nproc; ++t) counts.push_back(t);
        } else if (n.IsSequence()) {
            read_list(c_, n, path, [&](const YAML::Node& item, const std::string& p) {
                if (auto v = read_int(c_, item, p, 1, 1024)) {
                    if (std::find(counts.begin(), counts.end(), int(*v)) != counts.end())
                        c_.error(item, p, "thread count " + std::to_string(*v) + " is listed twice");
                    else counts.push_back(int(*v));
                }
            });
        } else if (auto v = read_int(c_, n, path, 1, 1024)) {
            counts.push_back(int(*v));
        }
        if (counts.empty()) return;
        threads_node_ = n;
        threads_path_ = path;
        cfg_.thread_counts = counts;
        cfg_.render.threads = counts.front();
    }

    void read_ray_sets(const YAML::Node& n) {
        Fields f(c_, n, "ray_sets", {"sets", "ao", "diffuse", "random", "seed"});
        if (!f.ok()) return;
        RaySetsSpec spec;
        if (auto* e = f.find("sets")) {
            read_list(c_, e->value, f.child("sets"), [&](const YAML::Node& item, const std::string& p) {
                const auto name = read_string(c_, item, p);
                if (!name) return;
                const auto kind = parse_ray_set(*name);
                std::vector<std::string> names(ray_set_names().begin(), ray_set_names().end());
                if (!kind) c_.error(item, p, unknown_name("ray set", *name, names, did_you_mean(*name, names)));
                else if (std::find(spec.sets.begin(), spec.sets.end(), *kind) != spec.sets.end())
                    c_.error(item, p, "ray set '" + *name + "' is listed twice");
                else spec.sets.push_back(*kind);
            });
        } else {
            for (auto name : ray_set_names()) spec.sets.push_back(*parse_ray_set(name));
        }
        RaySetParams& r = spec.params;
        if (auto* e = f.find("ao")) {
            Fields ao(c_, e->value, f.child("ao"), {"samples", "distance"});
            if (auto* s = ao.find("samples"))
                if (auto v = read_int(c_, s->value, ao.child("samples"), 1, 1024)) r.ao_samples = int(*v);
            if (auto* s = ao.find("distance"))
                if (auto v = read_float(c_, s->value, ao.child("distance"), 0, 1e3, true)) r.ao_distance = *v;
        }
        if (auto* e = f.find("diffuse")) {
            Fields d(c_, e->value, f.child("diffuse"), {"bounces"});
            if (auto* s = d.find("bounces"))
                if (auto v = read_int(c_, s->value, d.child("bounces"), 1, 64)) r.diffuse_bounces = int(*v);
        }
        if (auto* e = f.find("random")) {
            Fields d(c_, e->value, f.child("random"), {"rays"});
            if (auto* s = d.find("rays"))
                if (auto v = read_int(c_, s->value, d.child("rays"), 1, int64_t(1) << 30)) r.random_rays = uint64_t(*v);
        }
        if (auto* e = f.find("seed"))
            if (auto v = read_int(c_, e->value, f.child("seed"), 0, std::numeric_limits<int64_t>::max()))
                r.seed = uint64_t(*v);
        check_ray_set_bytes(spec, f, n);
        cfg_.ray_sets = std::move(spec);
    }

    // Each set's rays and the reference's answers for them (and the measurement's second
    // counting trace) are held in memory: a set larger than kMaxRaySetBytes is refused
    // here, naming the key that makes it, not as std::bad_alloc in its rows.
    void check_ray_set_bytes(const RaySetsSpec& spec, const Fields& f, const YAML::Node& n) {
        const RenderSettings& r = cfg_.render;
        const uint64_t primary = uint64_t(r.width) * uint64_t(r.height) * uint64_t(r.spp);
        const auto node_of = [&](const char* group, const char* key) -> std::pair<YAML::Node, std::string> {
            if (auto* e = f.find(group))
                if (e->value.IsMap() && e->value[key]) return {e->value[key], f.child(group) + "." + key};
            return {n, "ray_sets"};
        };
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
                why =
                    "ray_sets.diffuse.bounces x width x height x spp = " + std::to_string(spec.params.diffuse_bounces) +
                    " x " + std::to_string(primary) + " = " + std::to_string(rays) + " rays";
            } else if (kind == RaySetKind::Random) {
                rays = spec.params.random_rays;
                at = node_of("random", "rays");
                why = "ray_sets.random.rays = " + std::to_string(rays) + " rays";
            }
            const uint64_t bytes = rays * kRaySetBytesPerRay;
            if (bytes <= kMaxRaySetBytes) continue;
            c_.error(at.first, at.second,
                     "ray set '" + std::string(ray_set_name(kind)) + "': " + why + ", " + std::to_string(bytes) +
                         " bytes with their answers (" + std::to_string(kRaySetBytesPerRay) + " a ray); at most " +
                         std::to_string(kMaxRaySetBytes) + " bytes (" +
                         std::to_string(kMaxRaySetBytes / kRaySetBytesPerRay) + " rays) a set");
        }
    }

    std::shared_ptr<const RaySet> read_rays(const YAML::Node& n, const std::string& path) {
        Fields f(c_, n, path, {"file"});
        auto* e = f.require("file");
        if (!e) return nullptr;
        auto file = read_string(c_, e->value, f.child("file"));
        if (!file) return nullptr;
        const std::string resolved = resolve(*file);
        if (auto it = ray_sets_.find(resolved); it != ray_sets_.end()) return it->second;
        if (!fs::is_regular_file(resolved)) {
            c_.error(e->value, f.child("file"), "no such ray file: " + resolved);
            return nullptr;
        }
        RayFileContents contents = read_ray_file(resolved, resolved);
        if (!contents.issues.empty()) {
            for (auto& issue : contents.issues) {
                issue.key_path = f.child("file");
                c_.issues.push_back(std::move(issue));
            }
            return nullptr;
        }
        auto set = std::make_shared<RaySet>(
            RaySet{resolved, fs::path(*file).lexically_normal().string(), std::move(contents.rays)});
        ray_sets_.emplace(resolved, set);
        return set;
    }

    std::optional<Camera> read_camera(const YAML::Node& n, const std::string& path) {
        Fields f(c_, n, path, {"eye", "look_at", "up", "fov"});
        if (!f.ok()) return std::nullopt;
        Camera cam;
        bool ok = true;
        auto vec = [&](const char* key, Vec3& out, bool required) {
            const auto* e = required ? f.require(key) : f.find(key);
            if (!e) {
                ok &= !required;
                return;
            }
            if (auto v = read_vec3(c_, e->value, f.child(key))) out = *v;
            else ok = false;
        };
        vec("eye", cam.eye, true);
        vec("look_at", cam.look_at, true);
        vec("up", cam.up, false);
        if (auto* e = f.find("fov")) {
            if (auto v = read_float(c_, e->value, f.child("fov"), 0, 179, true)) cam.fov_deg = *v;
            else ok = false;
        }
        if (!ok) return std::nullopt;
        const Vec3 view = cam.look_at - cam.eye;
        if (dot(view, view) == 0.0f) {
            c_.error(n, path, "eye and look_at are the same point: the camera has no view direction");
            return std::nullopt;
        }
        const Vec3 side = cross(view, cam.up);
        if (dot(side, side) == 0.0f) {
            c_.error(n, path, "up is parallel to the view direction (look_at - eye)");
            return std::nullopt;
        }
        return cam;
    }

    bool known_registry_model(const YAML::Node& n, const std::string& path, const std::string& name) {
        if (registry_.find(name)) return true;
        std::vector<std::string> names;
        for (const auto& e : registry_.entries()) names.push_back(e.name);
        c_.error(n, path,
                 "unknown model '" + name + "': not in the model registry (configs/models.yaml: " + join_names(names) +
                     "); a mesh file is written {path: FILE}");
        return false;
    }

    void read_model(const YAML::Node& n, const std::string& path) {
        ModelSpec m;
        m.mark = {c_.file, n.Mark().line + 1, n.Mark().column + 1};
        m.key_path = path;
        if (n.IsScalar()) {
            m.kind = ModelSpec::Kind::Registry;
            m.name = n.Scalar();
            if (!known_registry_model(n, path, m.name)) return;
            m.label = m.name;
            m.key = "registry:" + m.name;
            m.rays = default_rays_;
            finish_model(std::move(m));
            return;
        }
        if (!n.IsMap()) {
            c_.error(n, path,
                     std::string("expected a registry name or a mapping (name:, path:, procedural: or "
                                 "case:), got ") +
                         kind_of(n));
            return;
        }
        Fields f(c_, n, path, {});  // keys depend on the form: checked below
        const bool has_name = f.has("name"), has_path = f.has("path"), has_proc = f.has("procedural"),
                   has_case = f.has("case");
        if (int(has_name) + int(has_path) + int(has_proc) + int(has_case) != 1) {
            c_.error(n, path,
                     "a model needs exactly one of 'name' (registry model), 'path' (mesh file), "
                     "'procedural' (generated scene) or 'case' (robustness case)");
            return;
        }
        if (has_case) return read_cases(f, std::move(m));
        const char* form = has_name ? "name" : has_path ? "path" : "procedural";
        std::vector<std::string> allowed = {form, "camera", "rays", "label", "repetitions", "warmup"};
        const auto* given = f.find(form);
        auto value = read_string(c_, given->value, f.child(form));
        if (!value) return;
        m.name = *value;
        bool ok = true;
        const ProceduralInfo* proc = nullptr;
        if (has_name) {
            m.kind = ModelSpec::Kind::Registry;
            ok = known_registry_model(given->value, f.child(form), m.name);
            m.label = m.name;
            m.key = "registry:" + m.name;
            allowed.insert(allowed.end(), {"decimate", "subdivide"});
            if (ok) ok = read_transform(f, m);
        } else if (has_path) {
            m.kind = ModelSpec::Kind::Path;
            m.resolved_path = resolve(m.name);
            std::error_code ec;
            if (!fs::exists(m.resolved_path, ec)) {
                c_.error(given->value, f.child(form), "no such mesh file: " + m.resolved_path);
                ok = false;
            } else if (!fs::is_regular_file(m.resolved_path, ec)) {
                // a directory or a FIFO: there, but not something a mesh can be read from
                c_.error(given->value, f.child(form), "not a regular file (a mesh file is needed): " + m.resolved_path);
                ok = false;
            }
            m.label = m.name;
            m.key = "path:" + fs::path(m.name).lexically_normal().string();
        } else {
            m.kind = ModelSpec::Kind::Procedural;
            proc = find_procedural(m.name);
            if (!proc) {
                c_.error(
                    given->value, f.child(form),
                    unknown_name("procedural scene", m.name, names_of(procedural_registry(), &ProceduralInfo::name)));
                return;
            }
            for (const auto& s : proc->params) allowed.push_back(s.name);
        }
        for (const auto& e : f.entries()) {
            if (std::find(allowed.begin(), allowed.end(), e.key) != allowed.end()) continue;
            std::string what = proc ? "procedural scene '" + proc->name + "' has no parameter '" + e.key + "'"
                                    : "unknown key '" + e.key + "'";
            c_.error(e.key_node, f.child(e.key),
                     what + did_you_mean(e.key, allowed) + "; allowed here: " + join_names(allowed));
            ok = false;
        }
        if (proc) {
            std::string label;
            for (const auto& spec : proc->params) {
                const auto* e = f.find(spec.name);
                if (!e) continue;
                auto v = read_param_value(c_, e->value, f.child(spec.name), proc->name, spec);
                if (!v) {
                    ok = false;
                    continue;
                }
                m.procedural_params[spec.name] = *v;
                append_item(label, ",", spec.name, "=", *v);
            }
            if (ok) {
                ParamSet set = resolve_params(proc->name, proc->params, m.procedural_params, "procedural scene");
                m.procedural_canonical = set.canonical();
            }
            m.label = label.empty() ? proc->name : proc->name + "(" + label + ")";
            m.key = "procedural:" + proc->name + ":" + m.procedural_canonical;
        }
        if (auto* e = f.find("camera")) {
            m.camera = read_camera(e->value, f.child("camera"));
            if (!m.camera) ok = false;
            else {
                const Camera& cam = *m.camera;
                auto v3 = [](Vec3 v) { return format_float(v.x) + "," + format_float(v.y) + "," + format_float(v.z); };
                m.key += ";camera=" + v3(cam.eye) + ";" + v3(cam.look_at) + ";" + v3(cam.up) + ";" +
                    format_float(cam.fov_deg);
            }
        }
        if (auto* e = f.find("rays")) {
            m.rays = read_rays(e->value, f.child("rays"));
            if (!m.rays) ok = false;
        } else {
            m.rays = default_rays_;
        }
        if (auto* e = f.find("label"))
            if (auto s = read_string(c_, e->value, f.child("label"))) m.label = *s;
        ok &= read_effort(f, m.repetitions, m.warmup);
        if (ok) finish_model(std::move(m));
    }

    // `{case: ID}` or `{case: all}`: scenes of the extreme-case catalogue, each judged
    // against its requirements by every accelerator entry (robustness_cases.h). They bring
    // their own rays, so a camera, a ray file or a transform does not apply.
    void read_cases(const Fields& f, ModelSpec m) {
        bool ok = true;
        for (const auto& e : f.entries())
            if (e.key != "case" && e.key != "label") {
                c_.error(e.key_node, f.child(e.key),
                         "unknown key '" + e.key +
                             "' for a robustness case (a case brings "
                             "its own scene and rays); allowed here: case, label");
                ok = false;
            }
        const auto* given = f.find("case");
        auto id = read_string(c_, given->value, f.child("case"));
        if (!id || !ok) return;
        std::vector<std::string> ids;
        for (const auto& entry : robustness_case_list())
            if (*id == "all" || entry.id == *id) ids.push_back(entry.id);
        if (ids.empty()) {
            std::vector<std::string> known = names_of(robustness_case_list(), &RobustnessCaseEntry::id);
            known.insert(known.begin(), "all");
            c_.error(given->value, f.child("case"), unknown_name("robustness case", *id, known));
            return;
        }
        const auto* label = f.find("label");
        if (label && ids.size() > 1) {
            c_.error(label->key_node, f.child("label"), "one label cannot name every case: give `label` with one case");
            return;
        }
        for (const auto& case_id : ids) {
            ModelSpec one = m;
            one.kind = ModelSpec::Kind::Case;
            one.name = case_id;
            one.key = "case:" + case_id;
            one.label = "case-" + case_id + ":" + robustness_case_name(case_id);
            if (label)
                if (auto s = read_string(c_, label->value, f.child("label"))) one.label = *s;
            finish_model(std::move(one));
        }
    }

    // `decimate: N` or `subdivide: LEVELS` of a registry model: at most one, N below the
    // model's triangle count. The label and the key gain "@decimate=N", so every size is a
    // model of its own in the CSV and in combination ids.
    bool read_transform(const Fields& f, ModelSpec& m) {
        const auto* dec = f.find("decimate");
        const auto* sub = f.find("subdivide");
        if (!dec && !sub) return true;
        if (dec && sub) {
            c_.error(sub->key_node, f.child("subdivide"), "give one of 'decimate' and 'subdivide', not both");
            return false;
        }
        const ModelEntry* entry = registry_.find(m.name);
        ModelTransformSpec t;
        if (dec) {
            const int64_t below = int64_t(entry->triangles) - 1;
            if (below < 1) {
                c_.error(dec->value, f.child("decimate"), "model '" + m.name + "' is too small to decimate");
                return false;
            }
            auto v = read_int(c_, dec->value, f.child("decimate"), 1, below);
            if (!v) return false;
            t = {ModelTransformSpec::Kind::Decimate, uint64_t(*v)};
        } else {
            auto v = read_int(c_, sub->value, f.child("subdivide"), 1, 4);
            if (!v) return false;
            t = {ModelTransformSpec::Kind::Subdivide, uint64_t(*v)};
        }
        m.label += "@" + t.text();
        m.key += ";" + t.text();
        m.transform = t;
        return true;
    }

    // `repetitions` and `warmup` of a model or an accelerator entry (for the slow ones).
    bool read_effort(const Fields& f, std::optional<int>& repetitions, std::optional<int>& warmup) {
        bool ok = true;
        if (auto* e = f.find("repetitions")) {
            if (auto v = read_int(c_, e->value, f.child("repetitions"), 1, 1000)) repetitions = int(*v);
            else ok = false;
        }
        if (auto* e = f.find("warmup")) {
            if (auto v = read_int(c_, e->value, f.child("warmup"), 0, 100)) warmup = int(*v);
            else ok = false;
        }
        return ok;
    }

    void finish_model(ModelSpec m) {
        if (m.rays) m.key += ";rays=" + m.rays->display;
        cfg_.models.push_back(std::move(m));
    }

    // Two models with the same identity would be measured twice under one id; two with
    // the same label could not be told apart in the CSV. One pass with maps: a list of
    // 100,000 models is checked in well under a second.
    void check_models() {
        // Ray sets start from the camera's rays and their reference hits.
        for (const ModelSpec& m : cfg_.models)
            if (cfg_.ray_sets && (m.rays || m.kind == ModelSpec::Kind::Case))
                c_.issues.push_back(
                    {m.mark, m.key_path,
                     std::string("`ray_sets` are made from a model's camera view; ") +
                         (m.rays ? "this model traces a ray file" : "a robustness case is judged, not timed")});
        std::map<std::string, size_t> by_key, by_label;
        for (size_t i = 0; i < cfg_.models.size(); ++i) {
            const ModelSpec& b = cfg_.models[i];
            const auto [key, new_key] = by_key.emplace(b.key, i);
            const auto [label, new_label] = by_label.emplace(b.label, i);
            if (!new_key) {
                const ModelSpec& a = cfg_.models[key->second];
                c_.issues.push_back({b.mark, b.key_path, "the same model as " + a.key_path + " ('" + a.label + "')"});
            } else if (!new_label) {
                const ModelSpec& a = cfg_.models[label->second];
                c_.issues.push_back(
                    {b.mark, b.key_path,
                     "the same label '" + b.label + "' as " + a.key_path + ": give one of them a distinct `label:`"});
            }
        }
    }

    // A structure with a `threads` parameter of its own builds with the render thread
    // count unless its entry gives one: a count outside that parameter's range is named
    // here, at render.threads, not later as the structure's parameter without a place.
    void check_thread_counts() {
        if (!threads_node_) return;
        for (const AcceleratorSpec& a : cfg_.accelerators) {
            const AcceleratorInfo* info = find_accelerator(a.name);
            if (!info) continue;
            bool given = false;
            for (const ParamAxis& axis : a.axes)
                for (const std::string& name : axis.names) given |= name == "threads";
            if (given) continue;
            for (const ParamSpec& spec : info->params) {
                if (spec.name != "threads") continue;
                for (int t : cfg_.thread_counts)
                    if (double(t) < spec.min || double(t) > spec.max) {
                        c_.error(*threads_node_, threads_path_,
                                 "thread count " + std::to_string(t) + " is outside the range of " + a.key_path +
                                     " ('" + a.name + "')'s own `threads` parameter, [" + format_float(spec.min) +
                                     ", " + format_float(spec.max) +
                                     "], which takes the render thread count: fewer threads, or give that entry "
                                     "params: {threads: N}");
                        break;
                    }
            }
        }
    }

    // The number of combinations (models x the sum over accelerator entries of the product
    // of their axes x thread counts x ray sets) is bounded before anything is expanded: three ranges of 10,000 values
    // each would otherwise allocate 10^12 combinations, with --dry-run too.
    void check_combination_count(const Fields& top) {
        uint64_t per_model = 0;
        bool over = false;
        for (const auto& a : cfg_.accelerators) {
            uint64_t product = 1;
            for (const auto& axis : a.axes)
                over |= __builtin_mul_overflow(product, uint64_t(axis.values.size()), &product);
            over |= __builtin_add_overflow(per_model, product, &per_model);
        }
        // Every model, thread count and ray set is a combination of each setting.
        const uint64_t sets = cfg_.ray_sets ? std::max<uint64_t>(1, cfg_.ray_sets->sets.size()) : 1;
        const uint64_t threads = std::max<uint64_t>(1, cfg_.thread_counts.size());
        uint64_t total = 0;
        over |= __builtin_mul_overflow(per_model, uint64_t(cfg_.models.size()), &total);
        over |= __builtin_mul_overflow(total, threads, &total);
        over |= __builtin_mul_overflow(total, sets, &total);
        if (over || total > kMaxCombinations) {
            const auto* e = top.find("accelerators");
            c_.error(e ? e->value : top.node(), "accelerators",
                     "the config expands to " + (over ? std::string("more than 2^64") : std::to_string(total)) +
                         " combinations (" + std::to_string(cfg_.models.size()) +
                         (cfg_.models.size() == 1 ? " model x " : " models x ") +
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
    void check_reference_size() {
        if (!cfg_.errors) return;
        const RenderSettings& r = cfg_.render;
        const uint64_t camera_rays = uint64_t(r.width) * uint64_t(r.height) * uint64_t(r.spp);
        uint64_t most = 0;
        const ModelSpec* worst = nullptr;
        for (const auto& m : cfg_.models) {
            if (m.kind == ModelSpec::Kind::Case) continue;  // its own small ray set
            const uint64_t rays = m.rays ? uint64_t(m.rays->rays.size()) : camera_rays;
            if (rays > most) most = rays, worst = &m;
        }
        if (most <= kMaxReferenceRays) return;
        const std::string what = worst->rays
            ? "the ray file " + worst->rays->display + " has " + std::to_string(most) + " rays"
            : "render: width x height x spp = " + std::to_string(most) + " primary rays";
        c_.issues.push_back({worst->mark, worst->key_path,
                             what +
                                 "; with error columns the reference keeps a 16-byte hit per primary ray (twice, "
                                 "with the measurement's), at most " +
                                 std::to_string(kMaxReferenceRays) +
                                 " rays: a smaller image or spp, or errors: false"});
    }

    void read_accelerator(const YAML::Node& n, const std::string& path) {
        AcceleratorSpec a;
        a.mark = {c_.file, n.Mark().line + 1, n.Mark().column + 1};
        a.key_path = path;
        Fields f(c_, n, path, {"name", "params", "repetitions", "warmup"});
        const auto* ne = f.require("name");
        if (!ne) return;
        auto name = read_string(c_, ne->value, f.child("name"));
        if (!name) return;
        a.name = *name;
        const AcceleratorInfo* info = find_accelerator(a.name);
        if (!info) {
            const auto names = names_of(accelerator_registry(), &AcceleratorInfo::name);
            c_.error(ne->value, f.child("name"),
                     unknown_name("accelerator", a.name, names, did_you_mean(a.name, names)));
            return;
        }
        bool ok = read_effort(f, a.repetitions, a.warmup);
        // Parameter errors name the accelerator, as in `accelerators[2].kdtree.max_depth`.
        const std::string base = path + "." + a.name;
        if (auto* pe = f.find("params")) {
            Fields pf(c_, pe->value, base, {});
            ok &= pf.ok();
            std::map<std::string, std::string> used;  // parameter -> the key that gave it
            for (const auto& e : pf.entries()) {
                std::vector<std::string> names;
                const bool group = e.key.size() >= 2 && e.key.front() == '[' && e.key.back() == ']';
                if (group) {
                    names = split_group(e.key);
                    if (names.size() < 2) {
                        c_.error(e.key_node, pf.child(e.key),
                                 "a zipped group names two or more parameters, e.g. "
                                 "\"[max_prims, max_depth]\"");
                        ok = false;
                        continue;
                    }
                } else {
                    names = {e.key};
                }
                bool names_ok = true;
                std::vector<const ParamSpec*> specs;
                for (const auto& pn : names) {
                    const ParamSpec* spec = find_spec(info->params, pn);
                    if (!spec) {
                        const auto known = spec_names(info->params);
                        c_.error(e.key_node, base + "." + pn,
                                 "accelerator '" + a.name + "' has no parameter '" + pn + "'" +
                                     did_you_mean(pn, known) +
                                     (known.empty() ? " (it takes none)" : " (it has: " + join_names(known) + ")"));
                        names_ok = false;
                        continue;
                    }
                    if (auto u = used.find(pn); u != used.end()) {
                        c_.error(e.key_node, base + "." + pn,
                                 "parameter '" + pn + "' is given twice (also in '" + u->second + "')");
                        names_ok = false;
                        continue;
                    }
                    used.emplace(pn, e.key);
                    specs.push_back(spec);
                }
                if (!names_ok) {
                    ok = false;
                    continue;
                }
                ParamAxis axis;
                axis.names = names;
                if (group) ok &= read_group_values(e.value, base, e.key, a.name, specs, axis);
                else ok &= read_values(e.value, base + "." + names[0], a.name, *specs[0], axis);
                a.axes.push_back(std::move(axis));
            }
        }
        if (ok) cfg_.accelerators.push_back(std::move(a));
    }

    static std::vector<std::string> split_group(const std::string& key) {
        std::vector<std::string> names;
        std::string inner = key.substr(1, key.size() - 2);
        size_t start = 0;
        for (;;) {
            size_t comma = inner.find(',', start);
            std::string part = inner.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
            size_t b = part.find_first_not_of(" \t"), e = part.find_last_not_of(" \t");
            names.push_back(b == std::string::npos ? "" : part.substr(b, e - b + 1));
            if (comma == std::string::npos) return names;
            start = comma + 1;
        }
    }

    // A parameter's values: a scalar (one value) or a list of scalars.
    bool read_values(const YAML::Node& n, const std::string& path, const std::string& accel, const ParamSpec& spec,
                     ParamAxis& axis) {
        if (n.IsScalar()) {
            auto v = read_param_value(c_, n, path, accel, spec);
            if (v) axis.values.push_back({*v});
            return bool(v);
        }
        if (n.IsMap()) return read_range(n, path, accel, spec, axis);
        if (!n.IsSequence() || n.size() == 0) {
            c_.error(n, path,
                     std::string("expected a value, a non-empty list of values or a range, got ") +
                         (n.IsSequence() ? "an empty list" : kind_of(n)));
            return false;
        }
        bool ok = true;
        for (size_t j = 0; j < n.size(); ++j) {
            const std::string p = path + "[" + std::to_string(j) + "]";
            auto v = read_param_value(c_, n[j], p, accel, spec);
            if (!v) {
                ok = false;
                continue;
            }
            if (std::find(axis.values.begin(), axis.values.end(), std::vector<std::string>{*v}) != axis.values.end()) {
                c_.error(n[j], p, "value " + *v + " is listed twice");
                ok = false;
                continue;
            }
            axis.values.push_back({*v});
        }
        return ok;
    }

    // A range (for grid searches; analysis/README.md "Grid search" and grid_config.py
    // expand it the same way): {from: a, to: b, step: s} is a, a+s, ... while <= b (with a
    // 1e-9 x s slack); {from: a, to: b, scale: log2|log10} is a, 2a, 4a, ... (10a, ...)
    // while <= b. Integer from, to (and step) give integers, other values are rounded to 12
    // significant digits (0.1 steps read 0.3, not 0.30000000000000004).
    bool read_range(const YAML::Node& n, const std::string& path, const std::string& accel, const ParamSpec& spec,
                    ParamAxis& axis) {
        constexpr size_t kMaxValues = 10000;  // a typo like step: 0.0001 must not hang the expansion
        Fields f(c_, n, path, {"from", "to", "step", "scale"});
        const auto* from = f.require("from");
        const auto* to = f.require("to");
        if (!from || !to) return false;
        auto lo = read_number(c_, from->value, f.child("from"), -1e300, 1e300, false);
        auto hi = read_number(c_, to->value, f.child("to"), -1e300, 1e300, false);
        if (!lo || !hi) return false;
        auto integral = [](const YAML::Node& v) {
            int64_t x;
            const std::string& t = v.Scalar();
            auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), x);
            return ec == std::errc() && p == t.data() + t.size();
        };
        if (*lo > *hi) {
            c_.error(n, path, "`from` (" + from->value.Scalar() + ") is above `to` (" + to->value.Scalar() + ")");
            return false;
        }
        const auto* step = f.find("step");
        const auto* scale = f.find("scale");
        if (bool(step) == bool(scale)) {
            c_.error(n, path, "a range gives exactly one of `step` or `scale` (log2, log10)");
            return false;
        }
        std::vector<double> values;
        bool integers = integral(from->value) && integral(to->value);
        if (step) {
            auto s = read_number(c_, step->value, f.child("step"), 0, 1e300, true);
            if (!s) return false;
            integers &= integral(step->value);
            const double count = std::floor((*hi - *lo) / *s + 1e-9) + 1;
            for (double i = 0; i < count && values.size() <= kMaxValues; ++i) values.push_back(*lo + i * *s);
        } else {
            auto name = read_string(c_, scale->value, f.child("scale"));
            if (!name) return false;
            if (*name != "log2" && *name != "log10") {
                c_.error(scale->value, f.child("scale"), "scale is log2 or log10, got '" + *name + "'");
                return false;
            }
            if (*lo <= 0) {
                c_.error(from->value, f.child("from"), "a " + *name + " range starts above 0");
                return false;
            }
            const double base = *name == "log2" ? 2.0 : 10.0;
            integers = integral(from->value);
            const double count = std::floor(std::log(*hi / *lo) / std::log(base) + 1e-9) + 1;
            for (double i = 0; i < count && values.size() <= kMaxValues; ++i) values.push_back(*lo * std::pow(base, i));
        }
        if (values.size() > kMaxValues) {
            c_.error(n, path, "the range has more than " + std::to_string(kMaxValues) + " values");
            return false;
        }
        bool ok = true;
        for (double v : values) {
            char text[40];
            if (integers) std::snprintf(text, sizeof text, "%.0f", v);
            else std::snprintf(text, sizeof text, "%.12g", v);
            try {
                const std::string canonical = format_param(parse_param(accel, spec, text));
                if (std::find(axis.values.begin(), axis.values.end(), std::vector<std::string>{canonical}) ==
                    axis.values.end())
                    axis.values.push_back({canonical});
            } catch (const ParamError& e) {
                c_.error(n, path, "the range's value " + std::string(text) + ": " + strip_param_prefix(e.what()));
                ok = false;
            }
        }
        return ok;
    }

    // A zipped group's values: a list of tuples, one value per named parameter.
    bool read_group_values(const YAML::Node& n, const std::string& base, const std::string& key,
                           const std::string& accel, const std::vector<const ParamSpec*>& specs, ParamAxis& axis) {
        const std::string path = base + "." + key;
        if (!n.IsSequence() || n.size() == 0) {
            c_.error(n, path,
                     "expected a non-empty list of tuples, e.g. [[1, 28], [10, 20]], got " +
                         std::string(n.IsSequence() ? "an empty list" : kind_of(n)));
            return false;
        }
        bool ok = true;
        for (size_t j = 0; j < n.size(); ++j) {
            const YAML::Node& t = n[j];
            const std::string tp = path + "[" + std::to_string(j) + "]";
            if (!t.IsSequence() || t.size() != specs.size()) {
                c_.error(t, tp,
                         "expected a tuple of " + std::to_string(specs.size()) + " values (" + key + "), got " +
                             (t.IsSequence() ? "a list of " + std::to_string(t.size()) : std::string(kind_of(t))));
                ok = false;
                continue;
            }
            std::vector<std::string> tuple;
            for (size_t k = 0; k < specs.size(); ++k) {
                auto v = read_param_value(c_, t[k], base + "." + specs[k]->name + "[" + std::to_string(j) + "]", accel,
                                          *specs[k]);
                if (v) tuple.push_back(*v);
            }
            if (tuple.size() != specs.size()) {
                ok = false;
                continue;
            }
            if (std::find(axis.values.begin(), axis.values.end(), tuple) != axis.values.end()) {
                c_.error(t, tp, "this tuple is listed twice");
                ok = false;
                continue;
            }
            axis.values.push_back(std::move(tuple));
        }
        return ok;
    }

    void read_skip(const YAML::Node& n, const std::string& path) {
        Fields f(c_, n, path, {"accel", "model", "triangles_above", "triangles_below", "params", "reason"});
        if (!f.ok()) return;
        SkipRule r;
        r.key_path = path;
        bool ok = true;
        if (const auto* e = f.require("reason")) {
            if (auto s = read_string(c_, e->value, f.child("reason"))) r.reason = *s;
            else ok = false;
        } else {
            ok = false;
        }
        const AcceleratorInfo* info = nullptr;
        if (const auto* e = f.find("accel")) {
            auto s = read_string(c_, e->value, f.child("accel"));
            if (s && !(info = find_accelerator(*s))) {
                c_.error(e->value, f.child("accel"), "unknown accelerator '" + *s + "'");
                s.reset();
            }
            if (s) r.accel = *s;
            else ok = false;
        }
        if (const auto* e = f.find("model")) {
            auto s = read_string(c_, e->value, f.child("model"));
            bool known = false;
            for (const auto& m : cfg_.models) known |= s && m.label == *s;
            if (s && !known) {
                std::vector<std::string> labels;
                for (const auto& m : cfg_.models) labels.push_back(m.label);
                c_.error(e->value, f.child("model"),
                         "'" + *s + "' matches no model of this config (" + join_names(labels) + ")");
                s.reset();
            }
            if (s) r.model = *s;
            else ok = false;
        }
        for (const char* key : {"triangles_above", "triangles_below"})
            if (const auto* e = f.find(key)) {
                auto v = read_int(c_, e->value, f.child(key), 0, int64_t(1) << 50);
                if (!v) ok = false;
                else (std::string(key) == "triangles_above" ? r.triangles_above : r.triangles_below) = uint64_t(*v);
            }
        if (const auto* e = f.find("params")) {
            if (!f.has("accel")) {
                c_.error(e->key_node, f.child("params"),
                         "matching on params needs `accel:` (parameters belong to one accelerator)");
                ok = false;
            } else if (info) {
                Fields pf(c_, e->value, f.child("params"), spec_names(info->params));
                ok &= pf.ok();
                for (const auto& pe : pf.entries()) {
                    auto v =
                        read_param_value(c_, pe.value, pf.child(pe.key), info->name, *find_spec(info->params, pe.key));
                    if (v) r.params[pe.key] = *v;
                    else ok = false;
                }
            }
        }
        if (!f.has("accel") && !f.has("model") && !f.has("triangles_above") && !f.has("triangles_below") &&
            !f.has("params")) {
            c_.error(n, path,
                     "a skip rule needs at least one condition (accel, model, triangles_above, "
                     "triangles_below, params)");
            ok = false;
        }
        if (ok) cfg_.skip.push_back(std::move(r));
    }

    Checker c_;
    Config cfg_;
    const ModelRegistry& registry_;
    std::shared_ptr<const RaySet> default_rays_;
    std::map<std::string, std::shared_ptr<const RaySet>> ray_sets_;
    std::optional<YAML::Node> threads_node_;  // render.threads, when given
    std::string threads_path_;
};

}  // namespace

Config load_config(const std::string& path, const ModelRegistry& models) { return Loader(path, models).load(); }

}  // namespace accelbench
