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

const std::vector<AcceleratorInfo>& accelerator_registry() {
    static const std::vector<AcceleratorInfo> registry = {
        BruteForce::info(),     Bvh::info(),  EmbreeAccel::info(), Lbvh::info(), KdTree::info(),
        ReferenceAccel::info(), Wbvh::info(),
    };
    return registry;
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
