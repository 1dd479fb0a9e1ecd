#include "accelbench/accel/registry.h"
#include "accelbench/base/unknown_name.h"

#include "accelbench/accel/baseline/brute_force.h"
#include "accelbench/accel/baseline/embree_accel.h"
#include "accelbench/accel/baseline/reference.h"
#include "accelbench/accel/bvh/bvh.h"
#include "accelbench/accel/bvh/lbvh.h"
#include "accelbench/accel/bvh/wbvh.h"
#include "accelbench/accel/kdtree/kdtree.h"
#include "accelbench/accel/plugin/plugin_accel.h"

#include <filesystem>

namespace accelbench {

const char* to_string(StructureRole role) {
    switch (role) {
        case StructureRole::ours: return "ours";
        case StructureRole::baseline: return "baseline";
        case StructureRole::reference: return "reference";
        case StructureRole::plugin: return "plugin";
    }
    return "?";
}

namespace {

AcceleratorInfo with_entry(AcceleratorInfo info, StructureEntry entry) {
    info.table = std::move(entry);
    return info;
}

// The structure table, in the order the analysis shows it: the report's structures (BVH,
// LBVH, kd-tree), ours beyond it, the baseline, the references; then the structures of
// plugins in the order they were loaded.
std::vector<AcceleratorInfo>& registry_entries() {
    using enum StructureRole;
    static std::vector<AcceleratorInfo> registry = {
        with_entry(Bvh::info(), {.family = "BVH", .variants = {{"split", {"median", "sah"}}}}),
        with_entry(Lbvh::info(), {.family = "BVH"}),
        with_entry(KdTree::info(), {.family = "kd-tree"}),
        with_entry(Wbvh::info(), {.family = "wide BVH", .variants = {{"width", {"4", "8"}}}}),
        with_entry(EmbreeAccel::info(), {.role = baseline, .family = "BVH"}),
        with_entry(BruteForce::info(), {.role = reference, .family = "none", .slow = true}),
        with_entry(ReferenceAccel::info(), {.role = reference, .family = "BVH"}),
    };
    return registry;
}
}  // namespace

const std::vector<AcceleratorInfo>& accelerator_registry() { return registry_entries(); }

void register_plugin(const std::string& path, const std::string& sha256) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path file = fs::weakly_canonical(path, ec);
    for (const AcceleratorInfo& info : registry_entries())
        if (info.plugin && fs::weakly_canonical(info.plugin->file, ec) == file) return;  // loaded already
    LoadedPlugin plugin = load_plugin(path, sha256);
    for (const AcceleratorInfo& info : plugin.structures)
        if (const AcceleratorInfo* other = find_accelerator(info.name))
            throw PluginError("plugin " + path + ": structure '" + info.name + "' is already registered " +
                              (other->plugin ? "by plugin " + other->plugin->file : std::string("(built in)")));
    for (AcceleratorInfo& info : plugin.structures) {
        info.table.role = StructureRole::plugin;
        if (info.table.family.empty()) info.table.family = "plugin";
        registry_entries().push_back(std::move(info));
    }
}

std::vector<std::map<std::string, std::string>> variant_settings(const AcceleratorInfo& info) {
    std::vector<std::map<std::string, std::string>> settings = {{}};
    for (const StructureVariants& v : info.table.variants) {
        std::vector<std::map<std::string, std::string>> next;
        for (const auto& s : settings)
            for (const std::string& value : v.values) {
                auto with = s;
                with[v.param] = value;
                next.push_back(std::move(with));
            }
        settings = std::move(next);
    }
    return settings;
}

const AcceleratorInfo* find_accelerator(std::string_view name) {
    for (const auto& info : accelerator_registry())
        if (info.name == name) return &info;
    return nullptr;
}

std::unique_ptr<Accelerator> make_accelerator(const std::string& name, const std::map<std::string, std::string>& params,
                                              ParamSet* resolved) {
    const AcceleratorInfo* info = find_accelerator(name);
    if (!info)
        throw ParamError(unknown_name("accelerator", name, names_of(accelerator_registry(), &AcceleratorInfo::name)));
    ParamSet set = resolve_params(name, info->params, params);
    auto accel = info->create(set);
    if (resolved) *resolved = std::move(set);
    return accel;
}

}  // namespace accelbench
