// `accelerators:`: each entry one registered structure with its parameter axes, or
// `{name: all, except: [...], params: {NAME: {...}}}`, every structure of the comparison
// (registry order; not the references, not the slow ones) but those excepted, each with
// the variants its row of the structure table declares (the BVH's splits, the wide BVH's
// widths) and at its defaults otherwise, unless `params` gives some.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <set>

#include "accelbench/accel/registry.h"
#include "accelbench/base/unknown_name.h"
#include "config/config_sections.h"

namespace accelbench {

namespace {

// The name of every registered structure, in registry order.
std::vector<std::string> structure_names() { return names_of(accelerator_registry(), &AcceleratorInfo::name); }

// A structure's name as `except` and `params` of the all form give it: a registered one,
// else an issue naming the known ones.
bool known_structure(ConfigReader& r, const YAML::Node& n, const std::string& path, const std::string& name) {
    if (find_accelerator(name)) return true;
    const auto names = structure_names();
    r.c.error(n, path, unknown_name("accelerator", name, names, did_you_mean(name, names)));
    return false;
}

// Whether `{name: all}` runs the structure: a structure of the comparison (not a
// reference) that is not slow. A config names the others to run them.
bool in_all(const AcceleratorInfo& info) { return info.table.role != StructureRole::reference && !info.table.slow; }

std::string why_not_in_all(const AcceleratorInfo& info) {
    return info.table.slow ? "slow (O(N) or worse per ray)" : std::string("a ") + to_string(info.table.role);
}

// `except: [NAME, ...]`: registered names `all` runs, each once.
std::set<std::string> read_except(ConfigReader& r, const Fields& f) {
    std::set<std::string> except;
    const auto* e = f.find("except");
    if (!e) return except;
    read_list(r.c, e->value, f.child("except"), [&](const YAML::Node& item, const std::string& p) {
        const auto name = read_string(r.c, item, p);
        if (!name || !known_structure(r, item, p, *name)) return;
        if (const AcceleratorInfo& info = *find_accelerator(*name); !in_all(info))
            r.c.error(item, p, "'" + *name + "' is not in `all` (" + why_not_in_all(info) + "): nothing to except");
        else if (!except.insert(*name).second) r.c.error(item, p, "'" + *name + "' is excepted twice");
    });
    return except;
}

// The axes of one structure in the all form: its declared variants (each value another
// structure of the tables) unless `params` sets that parameter, then what `params` gives.
std::vector<ParamAxis> all_form_axes(const AcceleratorInfo& info, std::vector<ParamAxis> given) {
    std::vector<ParamAxis> axes;
    for (const StructureVariants& v : info.table.variants) {
        const bool set = std::any_of(given.begin(), given.end(), [&](const ParamAxis& a) {
            return std::find(a.names.begin(), a.names.end(), v.param) != a.names.end();
        });
        if (set) continue;
        ParamAxis axis{{v.param}, {}};
        for (const auto& value : v.values) axis.values.push_back({value});
        axes.push_back(std::move(axis));
    }
    axes.insert(axes.end(), std::make_move_iterator(given.begin()), std::make_move_iterator(given.end()));
    return axes;
}

// `{name: all, ...}`: one AcceleratorSpec per registered structure not excepted. Parameter
// issues name the structure as a named entry's do: `accelerators[0].bvh.split`.
bool read_all_form(ConfigReader& r, const Fields& f, const AcceleratorSpec& entry) {
    const std::set<std::string> except = read_except(r, f);
    std::map<std::string, std::vector<ParamAxis>> axes;  // by structure, from `params`
    bool ok = true;
    if (const auto* pe = f.find("params")) {
        Fields pf(r.c, pe->value, f.child("params"), {});
        ok &= pf.ok();
        for (const auto& e : pf.entries()) {
            if (!known_structure(r, e.key_node, pf.child(e.key), e.key)) {
                ok = false;
            } else if (except.count(e.key)) {
                r.c.error(e.key_node, pf.child(e.key), "'" + e.key + "' is in `except`: it has no parameters to set");
                ok = false;
            } else if (const AcceleratorInfo& info = *find_accelerator(e.key); !in_all(info)) {
                r.c.error(
                    e.key_node, pf.child(e.key),
                    "'" + e.key + "' is not in `all` (" + why_not_in_all(info) + "): name it in an entry of its own");
                ok = false;
            } else {
                ok &=
                    read_param_axes(r.c, e.value, entry.key_path + "." + e.key, *find_accelerator(e.key), axes[e.key]);
            }
        }
    }
    if (except.size() == size_t(std::count_if(accelerator_registry().begin(), accelerator_registry().end(), in_all))) {
        r.c.error(f.find("except")->value, f.child("except"), "every structure is excepted: nothing is left to run");
        ok = false;
    }
    if (!ok) return false;
    for (const AcceleratorInfo& info : accelerator_registry()) {
        if (!in_all(info) || except.count(info.name)) continue;
        AcceleratorSpec a = entry;
        a.name = info.name;
        a.axes = all_form_axes(info, std::move(axes[info.name]));
        a.key_path = entry.key_path + " (all: " + info.name + ")";
        r.cfg.accelerators.push_back(std::move(a));
    }
    return true;
}

void read_accelerator(ConfigReader& r, const YAML::Node& n, const std::string& path) {
    AcceleratorSpec a;
    a.mark = {r.c.file, n.Mark().line + 1, n.Mark().column + 1};
    a.key_path = path;
    Fields f(r.c, n, path, {"name", "except", "params", "repetitions", "warmup", "processes"});
    const auto* ne = f.require("name");
    if (!ne) return;
    auto name = read_string(r.c, ne->value, f.child("name"));
    if (!name) return;
    a.name = *name;
    const bool all = a.name == "all";
    const AcceleratorInfo* info = all ? nullptr : find_accelerator(a.name);
    if (!all && !info) {
        auto names = structure_names();
        names.push_back("all");
        r.c.error(ne->value, f.child("name"), unknown_name("accelerator", a.name, names, did_you_mean(a.name, names)));
        return;
    }
    bool ok = read_effort(r, f, a.repetitions, a.warmup, a.processes);
    if (all) {
        if (ok) read_all_form(r, f, a);
        return;
    }
    if (const auto* e = f.find("except")) {
        r.c.error(e->key_node, f.child("except"), "`except` goes with `name: all` (every structure but those)");
        ok = false;
    }
    // Parameter errors name the accelerator, as in `accelerators[2].kdtree.max_depth`.
    if (const auto* pe = f.find("params")) ok &= read_param_axes(r.c, pe->value, path + "." + a.name, *info, a.axes);
    if (ok) r.cfg.accelerators.push_back(std::move(a));
}

}  // namespace

void read_accelerators(ConfigReader& r, const YAML::Node& n) {
    read_list(r.c, n, "accelerators",
              [&](const YAML::Node& item, const std::string& p) { read_accelerator(r, item, p); });
}

}  // namespace accelbench
