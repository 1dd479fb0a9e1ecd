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

namespace {
// The structures compiled in, then those of plugins in the order they were loaded.
std::vector<AcceleratorInfo>& registry_entries() {
    static std::vector<AcceleratorInfo> registry = {
        BruteForce::info(),     Bvh::info(),  EmbreeAccel::info(), Lbvh::info(), KdTree::info(),
        ReferenceAccel::info(), Wbvh::info(),
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
    for (AcceleratorInfo& info : plugin.structures) registry_entries().push_back(std::move(info));
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
