// The registry is the one list of structures: every entry carries what the harness and the
// analysis need (a label for every parameter setting), and labels tell structures apart.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <thread>

#include "accelbench/accel/registry.h"
#include "accelbench/base/param_table.h"
#include "test_scenes.h"

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

// Each structure's row of the structure table (`accelbench list --json`, which the analysis
// reads): a family, variants of declared parameters with accepted values and labels of their
// own, and one baseline that every ratio is taken against.
TEST(Registry, EveryStructureHasAFullRowOfTheStructureTable) {
    int baselines = 0;
    for (const auto& info : accelerator_registry()) {
        SCOPED_TRACE(info.name);
        EXPECT_FALSE(info.table.family.empty());
        baselines += info.table.role == StructureRole::baseline;
        std::set<std::string> labels;
        const auto settings = variant_settings(info);
        for (const auto& given : settings) {
            ParamSet set;
            ASSERT_NO_THROW(set = resolve_params(info.name, info.params, given));
            labels.insert(info.label(set));
        }
        EXPECT_EQ(labels.size(), settings.size()) << "two variants share a label";
        for (const auto& v : info.table.variants)
            EXPECT_TRUE(std::any_of(info.params.begin(), info.params.end(),
                                    [&](const ParamSpec& p) { return p.name == v.param; }))
                << v.param << " is not a declared parameter";
    }
    EXPECT_EQ(baselines, 1);
    const AcceleratorInfo* bvh = find_accelerator("bvh");
    ASSERT_NE(bvh, nullptr);
    EXPECT_EQ(variant_settings(*bvh).size(), 2u);  // median and SAH, two rows of the tables
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

// The parameters' names, order and defaults are what the CSV's `params` column and the
// combination ids hold: a refactoring must leave them exactly as they are (a new parameter
// changes them, and the regression baseline must then be measured again).
TEST(Registry, DefaultParameterTextIsUnchanged) {
    const std::map<std::string, std::string> expected = {
        {"brute_force", "max_triangles=20000;force=false"},
        {"bvh",
         "split=median;axis=longest;max_prims=auto;max_depth=50;bins=32;all_axes_min=1024;traversal_cost=4;"
         "isect_cost=1;traversal=ordered;leaf_test=auto;reinsertion=0;threads=1"},
        {"embree", "threads=1;quality=medium;robust=false;compact=false;max_isa=auto"},
        {"lbvh",
         "build=karras;bits=10;max_prims=1;max_depth=50;threads=1;task_threshold=100;sort_digit_bits=10;"
         "traversal=ordered"},
        {"kdtree",
         "build=nlogn;isect_cost=80;traversal_cost=1;empty_bonus=0.5;max_prims=1;max_depth=auto;mailbox=false;"
         "threads=1"},
        {"reference", "leaf_size=4"},
        {"wbvh",
         "width=8;max_prims=8;max_depth=64;bins=32;all_axes_min=0;traversal_cost=3;isect_cost=1;reinsertion=0;"
         "collapse=sah;packet_cost=2;kernel=simd;leaf_test=watertight;node_test=conservative;threads=1"},
    };
    for (const auto& [name, text] : expected) {
        const AcceleratorInfo* info = find_accelerator(name);
        ASSERT_NE(info, nullptr) << name;
        EXPECT_EQ(resolve_params(name, info->params, {}).canonical(), text) << name;
    }
}

// Every tree's statistics come from one tally (tree_tally.h): the same columns for every
// structure that has a tree, and the same rule for what cannot be known: no SAH cost for a
// root box without area, no average leaf without leaves.
TEST(BuildStats, EveryTreeReportsItsShapeTheSameWay) {
    const Scene grid = test::closed_grid();
    Scene line;  // degenerate triangles, all on the x axis: a root box without area
    for (int i = 0; i < 20; ++i)
        test::add_triangle(line, {float(i), 0, 0}, {float(i) + 1, 0, 0}, {float(i) + 0.5f, 0, 0});
    line.finalize();
    Scene empty;
    empty.finalize();
    int trees = 0;
    for (const auto& info : accelerator_registry()) {
        auto accel = info.create(resolve_params(info.name, info.params, {}));
        accel->build(grid);
        const BuildStats s = accel->build_stats();
        if (!s.nodes || *s.nodes == 0) continue;  // no tree (brute force) or none it shows (Embree)
        ++trees;
        ASSERT_TRUE(s.leaves && s.max_depth && s.memory_bytes) << info.name;
        EXPECT_GT(*s.leaves, 0u) << info.name;
        ASSERT_TRUE(s.avg_leaf_size.has_value()) << info.name;
        EXPECT_GT(*s.avg_leaf_size, 0.0) << info.name;
        ASSERT_TRUE(s.sah_cost.has_value()) << info.name;
        EXPECT_GE(*s.sah_cost, 1.0) << info.name << ": the root's own visit costs 1";

        accel->build(line);
        EXPECT_FALSE(accel->build_stats().sah_cost.has_value()) << info.name << ": a root box without area";
        accel->build(empty);
        const BuildStats e = accel->build_stats();
        EXPECT_FALSE(e.sah_cost.has_value()) << info.name << ": an empty scene";
        EXPECT_TRUE(e.leaves != 0u || !e.avg_leaf_size) << info.name << ": no leaves, no average";
    }
    EXPECT_GE(trees, 5);  // bvh, lbvh, kdtree, reference, wbvh, and any added since
}

// A structure's depth limit is what the robustness judge holds its tree to: built with it,
// the tree stays within it, and the structures with a depth parameter declare one.
TEST(Registry, DepthLimitBoundsTheBuiltTree) {
    const Scene grid = test::closed_grid();
    auto limit = [](const std::string& name, const std::map<std::string, std::string>& given) {
        const AcceleratorInfo* info = find_accelerator(name);
        return info->depth_limit(resolve_params(name, info->params, given));
    };
    for (const char* name : {"bvh", "lbvh", "kdtree", "wbvh"})
        for (const char* depth : {"0", "1", "3", "9"}) {
            const std::optional<uint64_t> bound = limit(name, {{"max_depth", depth}});
            ASSERT_TRUE(bound.has_value()) << name;
            EXPECT_EQ(*bound, std::string(name) == "wbvh" && std::string(depth) == "0" ? 1u : std::stoull(depth))
                << name << " max_depth=" << depth;
            auto accel = make_accelerator(name, {{"max_depth", depth}});
            accel->build(grid);
            EXPECT_LE(*accel->build_stats().max_depth, *bound) << name << " max_depth=" << depth;
        }
    EXPECT_FALSE(limit("kdtree", {}).has_value()) << "its default depth depends on the scene";
    EXPECT_FALSE(limit("reference", {}).has_value());
}

// A Config of every kind of row, to check that the declarations and Config::from come from
// the rows and the defaults from the member initializers.
enum class Shape { round, square };
constexpr std::array<std::string_view, 2> kShapeNames = {"round", "square"};
struct ToyConfig {
    uint32_t depth = 7;
    std::optional<int> leaf;
    int threads = 1;
    float cost = 0.25f;
    bool fast = true;
    Shape shape = Shape::square;
    uint32_t width = 8;
};
const ParamTable<ToyConfig>& toy_params() {
    static const ParamTable<ToyConfig> rows = {
        int_param("depth", &ToyConfig::depth, 0, 100, "depth"),
        auto_int_param("leaf", &ToyConfig::leaf, 1, 16, "leaf; auto = by scene"),
        threads_param("threads", &ToyConfig::threads, "threads"),
        float_param("cost", &ToyConfig::cost, 0, 10, "cost"),
        bool_param("fast", &ToyConfig::fast, "fast"),
        enum_param("shape", &ToyConfig::shape, kShapeNames, "shape"),
        choice_param("width", &ToyConfig::width, std::array<std::string_view, 2>{"4", "8"}, std::array{4u, 8u},
                     "width"),
    };
    return rows;
}

TEST(ParamTable, DeclaresEachRowWithTheConfigDefault) {
    const std::vector<ParamSpec> specs = toy_params().specs();
    ASSERT_EQ(specs.size(), 7u);
    EXPECT_EQ(resolve_params("toy", specs, {}).canonical(),
              "depth=7;leaf=auto;threads=1;cost=0.25;fast=true;shape=square;width=8");
    EXPECT_EQ(specs[0].type, ParamType::Int);
    EXPECT_EQ(specs[0].max, 100);
    EXPECT_TRUE(specs[1].scene_dependent_default);
    EXPECT_EQ(specs[3].type, ParamType::Float);
    EXPECT_EQ(specs[4].type, ParamType::Bool);
    EXPECT_EQ(specs[5].choices, (std::vector<std::string>{"round", "square"}));
    EXPECT_EQ(specs[6].choices, (std::vector<std::string>{"4", "8"}));
    EXPECT_THROW(resolve_params("toy", specs, {{"depth", "101"}}), ParamError);
}

TEST(ParamTable, FromStoresEveryGivenValueAndKeepsTheDefaultsOtherwise) {
    const ParamTable<ToyConfig>& t = toy_params();
    const ToyConfig d = t.from(resolve_params("toy", t.specs(), {}));
    EXPECT_EQ(d.depth, 7u);
    EXPECT_FALSE(d.leaf.has_value());
    EXPECT_EQ(d.threads, 1);
    EXPECT_EQ(d.cost, 0.25f);
    EXPECT_TRUE(d.fast);
    EXPECT_EQ(d.shape, Shape::square);
    EXPECT_EQ(d.width, 8u);
    const ToyConfig c = t.from(resolve_params("toy", t.specs(),
                                              {{"depth", "3"},
                                               {"leaf", "5"},
                                               {"threads", "0"},
                                               {"cost", "1.5"},
                                               {"fast", "false"},
                                               {"shape", "round"},
                                               {"width", "4"}}));
    EXPECT_EQ(c.depth, 3u);
    EXPECT_EQ(c.leaf, 5);
    EXPECT_EQ(c.threads, int(std::max(1u, std::thread::hardware_concurrency())));  // 0: every core
    EXPECT_EQ(c.cost, 1.5f);
    EXPECT_FALSE(c.fast);
    EXPECT_EQ(c.shape, Shape::round);
    EXPECT_EQ(c.width, 4u);
}

TEST(ParamTable, RefusesADefaultThatIsNoneOfTheChoices) {
    struct Odd {
        uint32_t width = 6;
    };
    EXPECT_THROW(choice_param("width", &Odd::width, std::array<std::string_view, 2>{"4", "8"}, std::array{4u, 8u}, ""),
                 std::logic_error);
}

}  // namespace
}  // namespace accelbench
