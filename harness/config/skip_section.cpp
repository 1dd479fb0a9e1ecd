// `skip:`: rules that turn matching combinations into `skipped` rows with their reason.
#include <yaml-cpp/yaml.h>

#include "accelbench/accel/registry.h"
#include "accelbench/base/unknown_name.h"
#include "config/config_sections.h"

namespace accelbench {

namespace {

void read_skip(ConfigReader& reader, const YAML::Node& n, const std::string& path) {
    Fields f(reader.c, n, path, {"accel", "model", "triangles_above", "triangles_below", "params", "reason"});
    if (!f.ok()) return;
    SkipRule rule;
    rule.key_path = path;
    bool ok = true;
    if (const auto* e = f.require("reason")) {
        if (auto s = read_string(reader.c, e->value, f.child("reason"))) rule.reason = *s;
        else ok = false;
    } else {
        ok = false;
    }
    const AcceleratorInfo* info = nullptr;
    if (const auto* e = f.find("accel")) {
        auto s = read_string(reader.c, e->value, f.child("accel"));
        if (s && !(info = find_accelerator(*s))) {
            reader.c.error(e->value, f.child("accel"), "unknown accelerator '" + *s + "'");
            s.reset();
        }
        if (s) rule.accel = *s;
        else ok = false;
    }
    if (const auto* e = f.find("model")) {
        auto s = read_string(reader.c, e->value, f.child("model"));
        bool known = false;
        for (const auto& m : reader.cfg.models) known |= s && m.label == *s;
        if (s && !known) {
            std::vector<std::string> labels;
            for (const auto& m : reader.cfg.models) labels.push_back(m.label);
            reader.c.error(e->value, f.child("model"),
                           "'" + *s + "' matches no model of this config (" + join_names(labels) + ")");
            s.reset();
        }
        if (s) rule.model = *s;
        else ok = false;
    }
    for (const char* key : {"triangles_above", "triangles_below"})
        if (const auto* e = f.find(key)) {
            auto v = read_int(reader.c, e->value, f.child(key), 0, int64_t(1) << 50);
            if (!v) ok = false;
            else (std::string(key) == "triangles_above" ? rule.triangles_above : rule.triangles_below) = uint64_t(*v);
        }
    if (const auto* e = f.find("params")) {
        if (!f.has("accel")) {
            reader.c.error(e->key_node, f.child("params"),
                           "matching on params needs `accel:` (parameters belong to one accelerator)");
            ok = false;
        } else if (info) {
            Fields pf(reader.c, e->value, f.child("params"), spec_names(info->params));
            ok &= pf.ok();
            for (const auto& pe : pf.entries()) {
                auto v = read_param_value(reader.c, pe.value, pf.child(pe.key), info->name,
                                          *find_spec(info->params, pe.key));
                if (v) rule.params[pe.key] = *v;
                else ok = false;
            }
        }
    }
    if (!f.has("accel") && !f.has("model") && !f.has("triangles_above") && !f.has("triangles_below") &&
        !f.has("params")) {
        reader.c.error(n, path,
                       "a skip rule needs at least one condition (accel, model, triangles_above, "
                       "triangles_below, params)");
        ok = false;
    }
    if (ok) reader.cfg.skip.push_back(std::move(rule));
}

}  // namespace

void read_skip_rules(ConfigReader& r, const YAML::Node& n) {
    read_list(
        r.c, n, "skip", [&](const YAML::Node& item, const std::string& p) { read_skip(r, item, p); }, true);
}

}  // namespace accelbench
