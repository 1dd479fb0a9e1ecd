// The registry is the one list of structures: every entry carries what the harness and the
// analysis need (a label for every parameter setting), and labels tell structures apart.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "accelbench/accel/registry.h"

namespace accelbench {
namespace {

TEST(Registry, EveryStructureHasALabelAtItsDefaults) {
    std::set<std::string> labels;
    for (const auto& info : accelerator_registry()) {
        ASSERT_TRUE(info.label) << info.name << " has no label function";
        const std::string label = info.label(resolve_params(info.name, info.params, {}));
        EXPECT_FALSE(label.empty()) << info.name;
        EXPECT_TRUE(labels.insert(label).second) << info.name << " shares its label '" << label << "'";
    }
}

TEST(Registry, LabelsFollowTheParametersThatMakeAnotherStructure) {
    auto label = [](const std::string& name, const std::map<std::string, std::string>& given) {
        const AcceleratorInfo* info = find_accelerator(name);
        return info->label(resolve_params(name, info->params, given));
    };
    EXPECT_EQ(label("wbvh", {}), "wide BVH (8, SIMD)");
    EXPECT_EQ(label("wbvh", {{"width", "4"}}), "wide BVH (4, SIMD)");
    EXPECT_EQ(label("wbvh", {{"width", "4"}, {"kernel", "scalar"}}), "wide BVH (4, scalar)");
    EXPECT_EQ(label("bvh", {}), "BVH (median)");
    EXPECT_EQ(label("bvh", {{"split", "sah"}}), "BVH (binned SAH)");
    EXPECT_EQ(label("kdtree", {}), "kd-tree");
    EXPECT_EQ(label("lbvh", {{"build", "report"}}), "LBVH");
}

}  // namespace
}  // namespace accelbench
