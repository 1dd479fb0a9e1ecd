// Stiff parameters: extreme values must either build a tree that terminates
// with bounded depth and memory and still answers correctly, or be refused up front with
// a message naming the parameter. On a dense cluster — thousands of overlapping
// triangles in a 1e-3 box — where a split criterion that never gives up would recurse to
// the depth limit everywhere.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "accelbench/accel/registry.h"
#include "accelbench/base/memory.h"
#include "accelbench/base/random.h"
#include "accelbench/verify/error_metrics.h"
#include "accelbench/verify/robustness_cases.h"
#include "agreement.h"

using namespace accelbench;

namespace {

// 4000 triangles, each with corners within 2e-4 of a centre inside [0, 1e-3]^3.
Scene dense_cluster() {
    Scene s;
    s.name = "dense-cluster";
    SplitMix64 rng(2024);
    for (uint32_t i = 0; i < 4000; ++i) {
        const Vec3 c = Vec3{rng.uniform(), rng.uniform(), rng.uniform()} * 1e-3f;
        for (int k = 0; k < 3; ++k) s.vertices.push_back(c + rng.unit_vector() * 2e-4f);
        s.triangles.push_back({3 * i, 3 * i + 1, 3 * i + 2});
    }
    s.finalize();
    return s;
}

struct Stiff {
    std::string accelerator;
    std::map<std::string, std::string> params;
};

void PrintTo(const Stiff& s, std::ostream* os);

std::vector<Stiff> stiff_settings() {
    return {
        {"kdtree", {{"max_depth", "100"}, {"max_prims", "1"}}},
        {"kdtree", {{"isect_cost", "1e4"}}},
        {"kdtree", {{"isect_cost", "1e-4"}}},
        {"kdtree", {{"traversal_cost", "1e4"}}},
        {"kdtree", {{"traversal_cost", "1e-4"}}},
        {"kdtree", {{"empty_bonus", "0.99"}}},
        {"kdtree", {{"max_depth", "100"}, {"max_prims", "1"}, {"isect_cost", "1e4"}, {"empty_bonus", "0.99"}}},
        {"bvh", {{"max_depth", "1"}}},
        {"bvh", {{"max_depth", "200"}}},
        {"bvh", {{"max_depth", "200"}, {"split", "sah"}}},
        {"lbvh", {{"max_depth", "1"}}},
        {"lbvh", {{"max_depth", "200"}}},
        {"lbvh", {{"bits", "1"}}},
    };
}

std::string label(const Stiff& s) {
    std::string out = s.accelerator;
    for (const auto& [k, v] : s.params) out += " " + k + "=" + v;
    return out;
}

void PrintTo(const Stiff& s, std::ostream* os) { *os << label(s); }

class StiffParams : public ::testing::TestWithParam<Stiff> {};

// A refusal must name one of the parameters that were given.
bool names_a_parameter(const std::string& message, const Stiff& s) {
    for (const auto& [k, v] : s.params)
        if (message.find(k) != std::string::npos) return true;
    return false;
}

TEST_P(StiffParams, TerminatesWithBoundedMemoryOrRefusesClearly) {
    const Stiff& stiff = GetParam();
    if (!find_accelerator(stiff.accelerator)) GTEST_SKIP() << stiff.accelerator << " is not registered in this build";
    static const Scene scene = dense_cluster();

    std::unique_ptr<Accelerator> accel;
    try {
        accel = make_accelerator(stiff.accelerator, stiff.params);
    } catch (const ParamError& e) {
        const std::string message = e.what();
        std::printf("[stiff] %s: refused up front: %s\n", label(stiff).c_str(), message.c_str());
        EXPECT_EQ(message.find("has no parameter"), std::string::npos) << message;
        EXPECT_TRUE(names_a_parameter(message, stiff)) << message;
        return;
    }
    const bool rss_reset = reset_peak_rss();
    const uint64_t rss_before = peak_rss_bytes();
    try {
        accel->build(scene);
    } catch (const std::exception& e) {
        const std::string message = e.what();
        std::printf("[stiff] %s: build refused: %s\n", label(stiff).c_str(), message.c_str());
        EXPECT_TRUE(names_a_parameter(message, stiff)) << "a refusal must name the limit: " << message;
        return;
    }
    const uint64_t rss_after = peak_rss_bytes();
    const BuildStats stats = accel->build_stats();
    const uint64_t memory_limit = case_memory_limit(scene);
    std::printf("[stiff] %s: built, depth %s, nodes %s, memory %s bytes (limit %llu), peak RSS +%llu KiB%s\n",
                label(stiff).c_str(), stats.max_depth ? std::to_string(*stats.max_depth).c_str() : "-",
                stats.nodes ? std::to_string(*stats.nodes).c_str() : "-",
                stats.memory_bytes ? std::to_string(*stats.memory_bytes).c_str() : "-",
                (unsigned long long)memory_limit, (unsigned long long)((rss_after - rss_before) / 1024),
                rss_reset ? "" : " (process-wide peak)");
    ASSERT_TRUE(stats.memory_bytes.has_value()) << "our structures report their memory";
    EXPECT_LE(*stats.memory_bytes, memory_limit);
    const AcceleratorInfo& info = *find_accelerator(stiff.accelerator);
    const auto limit = info.depth_limit(resolve_params(info.name, info.params, stiff.params));
    if (limit && stats.max_depth) {
        EXPECT_LE(*stats.max_depth, *limit);
    }
    EXPECT_LT(rss_after - rss_before, uint64_t(256) << 20) << "peak RSS grew by more than 256 MiB";

    // Still correct: the same answers as the reference (ties aside).
    auto reference = make_accelerator("reference", {});
    reference->build(scene);
    const std::vector<Ray> rays = test::probe_rays(scene, 2000, 11);
    std::vector<Hit> got(rays.size()), want(rays.size());
    accel->closest_hits(rays, got);
    reference->closest_hits(rays, want);
    const HitErrors e = compare_hits(got, want);
    EXPECT_EQ(e.false_misses, 0u);
    EXPECT_EQ(e.false_hits, 0u);
    EXPECT_EQ(e.prim_mismatches, 0u);
    EXPECT_EQ(e.nan_results, 0u);
}

INSTANTIATE_TEST_SUITE_P(ExtremeValues, StiffParams, ::testing::ValuesIn(stiff_settings()), [](const auto& info) {
    std::string name = info.param.accelerator;
    for (const auto& [k, v] : info.param.params) name += "_" + k + "_" + v;
    for (char& c : name)
        if (!isalnum(static_cast<unsigned char>(c))) c = '_';
    return name;
});

}  // namespace
