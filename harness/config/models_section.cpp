// `models:`: registry models (with an optional decimation or subdivision), mesh files,
// procedural scenes and robustness cases, each with its label and identity.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <map>

#include "accelbench/base/unknown_name.h"
#include "accelbench/scene/procedural.h"
#include "accelbench/verify/robustness_cases.h"
#include "config/config_sections.h"
#include "models/camera_yaml.h"
#include "models/model_registry.h"
#include "util/text.h"

namespace fs = std::filesystem;

namespace accelbench {

namespace {

bool known_registry_model(ConfigReader& r, const YAML::Node& n, const std::string& path, const std::string& name) {
    if (r.registry.find(name)) return true;
    std::vector<std::string> names;
    for (const auto& e : r.registry.entries()) names.push_back(e.name);
    r.c.error(n, path,
              "unknown model '" + name + "': not in the model registry (configs/models.yaml: " + join_names(names) +
                  "); a mesh file is written {path: FILE}");
    return false;
}

void finish_model(ConfigReader& r, ModelSpec m) {
    if (m.rays) m.key += ";rays=" + m.rays->display;
    r.cfg.models.push_back(std::move(m));
}

// `{case: ID}` or `{case: all}`: scenes of the extreme-case catalogue, each judged
// against its requirements by every accelerator entry (robustness_cases.h). They bring
// their own rays, so a camera, a ray file or a transform does not apply.
void read_cases(ConfigReader& r, const Fields& f, ModelSpec m) {
    bool ok = true;
    for (const auto& e : f.entries())
        if (e.key != "case" && e.key != "label") {
            r.c.error(e.key_node, f.child(e.key),
                      "unknown key '" + e.key +
                          "' for a robustness case (a case brings "
                          "its own scene and rays); allowed here: case, label");
            ok = false;
        }
    const auto* given = f.find("case");
    auto id = read_string(r.c, given->value, f.child("case"));
    if (!id || !ok) return;
    std::vector<std::string> ids;
    for (const auto& entry : robustness_case_list())
        if (*id == "all" || entry.id == *id) ids.push_back(entry.id);
    if (ids.empty()) {
        std::vector<std::string> known = names_of(robustness_case_list(), &RobustnessCaseEntry::id);
        known.insert(known.begin(), "all");
        r.c.error(given->value, f.child("case"), unknown_name("robustness case", *id, known));
        return;
    }
    const auto* label = f.find("label");
    if (label && ids.size() > 1) {
        r.c.error(label->key_node, f.child("label"), "one label cannot name every case: give `label` with one case");
        return;
    }
    for (const auto& case_id : ids) {
        ModelSpec one = m;
        one.kind = ModelSpec::Kind::Case;
        one.name = case_id;
        one.key = "case:" + case_id;
        one.label = "case-" + case_id + ":" + robustness_case_name(case_id);
        if (label)
            if (auto s = read_string(r.c, label->value, f.child("label"))) one.label = *s;
        finish_model(r, std::move(one));
    }
}

// `decimate: N` or `subdivide: LEVELS` of a registry model: at most one, N below the
// model's triangle count. The label and the key gain "@decimate=N", so every size is a
// model of its own in the CSV and in combination ids.
bool read_transform(ConfigReader& r, const Fields& f, ModelSpec& m) {
    const auto* dec = f.find("decimate");
    const auto* sub = f.find("subdivide");
    if (!dec && !sub) return true;
    if (dec && sub) {
        r.c.error(sub->key_node, f.child("subdivide"), "give one of 'decimate' and 'subdivide', not both");
        return false;
    }
    const ModelEntry* entry = r.registry.find(m.name);
    ModelTransformSpec t;
    if (dec) {
        const int64_t below = int64_t(entry->triangles) - 1;
        if (below < 1) {
            r.c.error(dec->value, f.child("decimate"), "model '" + m.name + "' is too small to decimate");
            return false;
        }
        auto v = read_int(r.c, dec->value, f.child("decimate"), 1, below);
        if (!v) return false;
        t = {ModelTransformSpec::Kind::Decimate, uint64_t(*v)};
    } else {
        auto v = read_int(r.c, sub->value, f.child("subdivide"), 1, 4);
        if (!v) return false;
        t = {ModelTransformSpec::Kind::Subdivide, uint64_t(*v)};
    }
    m.label.append("@").append(t.text());  // append: GCC 12's false -Wrestrict on "@" + std::string&&
    m.key.append(";").append(t.text());
    m.transform = t;
    return true;
}

// The path of a `{path: FILE}` model: there, and a regular file.
bool check_mesh_path(ConfigReader& r, const Fields::Entry& given, const std::string& path, const std::string& file) {
    std::error_code ec;
    if (!fs::exists(file, ec)) {
        r.c.error(given.value, path, "no such mesh file: " + file);
        return false;
    }
    if (!fs::is_regular_file(file, ec)) {
        // a directory or a FIFO: there, but not something a mesh can be read from
        r.c.error(given.value, path, "not a regular file (a mesh file is needed): " + file);
        return false;
    }
    return true;
}

// A procedural scene's parameters (the entry's other keys): the label shows those given,
// the key all of them, defaults filled in.
bool read_procedural_params(ConfigReader& r, const Fields& f, const ProceduralInfo& proc, bool ok, ModelSpec& m) {
    std::string label;
    for (const auto& spec : proc.params) {
        const auto* e = f.find(spec.name);
        if (!e) continue;
        auto v = read_param_value(r.c, e->value, f.child(spec.name), proc.name, spec);
        if (!v) {
            ok = false;
            continue;
        }
        m.procedural_params[spec.name] = *v;
        append_item(label, ",", spec.name, "=", *v);
    }
    if (ok) {
        ParamSet set = resolve_params(proc.name, proc.params, m.procedural_params, "procedural scene");
        m.procedural_canonical = set.canonical();
    }
    m.label = label.empty() ? proc.name : proc.name + "(" + label + ")";
    m.key = "procedural:" + proc.name + ":" + m.procedural_canonical;
    return ok;
}

// The options every mapping form takes: camera, rays, label, repetitions, warmup, processes.
bool read_model_options(ConfigReader& r, const Fields& f, ModelSpec& m) {
    bool ok = true;
    if (auto* e = f.find("camera")) {
        m.camera = read_camera(r.c, e->value, f.child("camera"));
        if (!m.camera) ok = false;
        else {
            const Camera& cam = *m.camera;
            auto v3 = [](Vec3 v) { return format_float(v.x) + "," + format_float(v.y) + "," + format_float(v.z); };
            m.key +=
                ";camera=" + v3(cam.eye) + ";" + v3(cam.look_at) + ";" + v3(cam.up) + ";" + format_float(cam.fov_deg);
        }
    }
    if (auto* e = f.find("rays")) {
        m.rays = read_rays(r, e->value, f.child("rays"));
        if (!m.rays) ok = false;
    } else {
        m.rays = r.default_rays;
    }
    if (auto* e = f.find("label"))
        if (auto s = read_string(r.c, e->value, f.child("label"))) m.label = *s;
    ok &= read_effort(r, f, m.repetitions, m.warmup, m.processes);
    return ok;
}

// `{name: ...}`, `{path: ...}` or `{procedural: ...}` with their options.
void read_model_mapping(ConfigReader& r, const Fields& f, const char* form, ModelSpec m) {
    std::vector<std::string> allowed = {form, "camera", "rays", "label", "repetitions", "warmup", "processes"};
    const auto* given = f.find(form);
    auto value = read_string(r.c, given->value, f.child(form));
    if (!value) return;
    m.name = *value;
    bool ok = true;
    const ProceduralInfo* proc = nullptr;
    if (std::string(form) == "name") {
        m.kind = ModelSpec::Kind::Registry;
        ok = known_registry_model(r, given->value, f.child(form), m.name);
        m.label = m.name;
        m.key = "registry:" + m.name;
        allowed.insert(allowed.end(), {"decimate", "subdivide"});
        if (ok) ok = read_transform(r, f, m);
    } else if (std::string(form) == "path") {
        m.kind = ModelSpec::Kind::Path;
        m.resolved_path = r.resolve(m.name);
        ok = check_mesh_path(r, *given, f.child(form), m.resolved_path);
        m.label = m.name;
        m.key = "path:" + fs::path(m.name).lexically_normal().string();
    } else {
        m.kind = ModelSpec::Kind::Procedural;
        proc = find_procedural(m.name);
        if (!proc) {
            r.c.error(given->value, f.child(form),
                      unknown_name("procedural scene", m.name, names_of(procedural_registry(), &ProceduralInfo::name)));
            return;
        }
        for (const auto& s : proc->params) allowed.push_back(s.name);
    }
    for (const auto& e : f.entries()) {
        if (std::find(allowed.begin(), allowed.end(), e.key) != allowed.end()) continue;
        std::string what = proc ? "procedural scene '" + proc->name + "' has no parameter '" + e.key + "'"
                                : "unknown key '" + e.key + "'";
        r.c.error(e.key_node, f.child(e.key),
                  what + did_you_mean(e.key, allowed) + "; allowed here: " + join_names(allowed));
        ok = false;
    }
    if (proc) ok = read_procedural_params(r, f, *proc, ok, m);
    ok &= read_model_options(r, f, m);
    if (ok) finish_model(r, std::move(m));
}

void read_model(ConfigReader& r, const YAML::Node& n, const std::string& path) {
    ModelSpec m;
    m.mark = {r.c.file, n.Mark().line + 1, n.Mark().column + 1};
    m.key_path = path;
    if (n.IsScalar()) {
        m.kind = ModelSpec::Kind::Registry;
        m.name = n.Scalar();
        if (!known_registry_model(r, n, path, m.name)) return;
        m.label = m.name;
        m.key = "registry:" + m.name;
        m.rays = r.default_rays;
        finish_model(r, std::move(m));
        return;
    }
    if (!n.IsMap()) {
        r.c.error(n, path,
                  std::string("expected a registry name or a mapping (name:, path:, procedural: or case:), got ") +
                      kind_of(n));
        return;
    }
    Fields f(r.c, n, path, {});  // keys depend on the form: checked below
    if (!f.ok()) return;         // a merge key that merged nothing: named already
    const bool has_name = f.has("name"), has_path = f.has("path"), has_proc = f.has("procedural"),
               has_case = f.has("case");
    if (int(has_name) + int(has_path) + int(has_proc) + int(has_case) != 1) {
        r.c.error(n, path,
                  "a model needs exactly one of 'name' (registry model), 'path' (mesh file), "
                  "'procedural' (generated scene) or 'case' (robustness case)");
        return;
    }
    if (has_case) return read_cases(r, f, std::move(m));
    read_model_mapping(r, f, has_name ? "name" : has_path ? "path" : "procedural", std::move(m));
}

// Two models with the same identity would be measured twice under one id; two with
// the same label could not be told apart in the CSV. One pass with maps: a list of
// 100,000 models is checked in well under a second.
void check_models(ConfigReader& r) {
    // Ray sets start from the camera's rays and their reference hits. A robustness case
    // brings its own rays and is judged once, as in any config (its leaks beside the
    // ray sets' speed: configs/ray-sets.yaml).
    for (const ModelSpec& m : r.cfg.models)
        if (r.cfg.ray_sets && m.rays)
            r.c.issues.push_back(
                {m.mark, m.key_path, "`ray_sets` are made from a model's camera view; this model traces a ray file"});
    std::map<std::string, size_t> by_key, by_label;
    for (size_t i = 0; i < r.cfg.models.size(); ++i) {
        const ModelSpec& b = r.cfg.models[i];
        // Every label, given or made from a path, a case or parameters: checked once here.
        if (const std::string why = control_character_problem(b.label); !why.empty())
            r.c.issues.push_back({b.mark, b.key_path, "the model's label " + json_quoted(b.label) + " " + why});
        const auto [key, new_key] = by_key.emplace(b.key, i);
        const auto [label, new_label] = by_label.emplace(b.label, i);
        if (!new_key) {
            const ModelSpec& a = r.cfg.models[key->second];
            r.c.issues.push_back({b.mark, b.key_path, "the same model as " + a.key_path + " ('" + a.label + "')"});
        } else if (!new_label) {
            const ModelSpec& a = r.cfg.models[label->second];
            r.c.issues.push_back(
                {b.mark, b.key_path,
                 "the same label '" + b.label + "' as " + a.key_path + ": give one of them a distinct `label:`"});
        }
    }
}

}  // namespace

void read_models(ConfigReader& r, const YAML::Node& n) {
    read_list(r.c, n, "models", [&](const YAML::Node& item, const std::string& p) { read_model(r, item, p); });
    check_models(r);
}

}  // namespace accelbench
