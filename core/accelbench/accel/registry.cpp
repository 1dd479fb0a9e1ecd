#include "accelbench/accel/registry.h"
#include "accelbench/base/unknown_name.h"

#include "accelbench/accel/baseline/brute_force.h"
#include "accelbench/accel/baseline/embree_accel.h"
#include "accelbench/accel/baseline/reference.h"
#include "accelbench/accel/bvh/bvh.h"
#include "accelbench/accel/bvh/lbvh.h"
#include "accelbench/accel/bvh/wbvh.h"
#include "accelbench/accel/kdtree/kdtree.h"

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

}  // namespace

// The structure table, in the order the analysis shows it: the report's structures (BVH,
// LBVH, kd-tree), ours beyond it, the baseline, then the references.
const std::vector<AcceleratorInfo>& accelerator_registry() {
    using enum StructureRole;
    static const std::vector<AcceleratorInfo> registry = {
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
