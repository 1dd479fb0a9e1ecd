// The LBVH: the tree against the split rule itself, agreement with Embree, the same tree
// for any thread count, exact trees on hand-made scenes and degenerate input.
#include "accelbench/accel/bvh/lbvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <string>
#include <utility>

#include "accelbench/accel/bvh/bvh.h"
#include "accelbench/accel/bvh/morton_code.h"
#include "accelbench/base/random.h"
#include "accelbench/scene/procedural.h"
#include "agreement.h"
#include "bvh_check.h"
#include "test_scenes.h"

using namespace accelbench;
using test::add_triangle;

namespace {

// The shared procedural soup: random triangles of edge `size` in the unit box.
Scene random_soup(int n, uint64_t seed, float size = 0.2f) {
    return make_procedural(
        "soup", {{"triangles", std::to_string(n)}, {"seed", std::to_string(seed)}, {"size", std::to_string(size)}});
}

// A w x h grid of squares (two triangles each) in the plane z = 0, slightly warped in z
// unless flat: neighbouring triangles share edges, where a non-watertight test leaks.
Scene grid_mesh(int w, int h, bool flat) {
    Scene s;
    s.name = flat ? "flat-grid" : "grid";
    for (int j = 0; j <= h; ++j)
        for (int i = 0; i <= w; ++i)
            s.vertices.push_back(
                {float(i), float(j), flat ? 0.0f : 0.3f * std::sin(0.7f * float(i) + 0.4f * float(j))});
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const uint32_t v = uint32_t(j * (w + 1) + i);
            s.triangles.push_back({v, v + 1, v + uint32_t(w) + 1});
            s.triangles.push_back({v + 1, v + uint32_t(w) + 2, v + uint32_t(w) + 1});
        }
    s.finalize();
    return s;
}

// Eight small triangles, one near each corner of the unit cube, numbered so that the
// triangle at corner (x, y, z) is number x + 2y + 4z: its Morton code's rank.
Scene cube_corners() {
    Scene s;
    s.name = "cube-corners";
    for (int i = 0; i < 8; ++i) {
        const Vec3 c{float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)};
        add_triangle(s, c + Vec3{-0.05f, -0.05f, 0}, c + Vec3{0.05f, -0.05f, 0}, c + Vec3{0, 0.05f, 0.02f});
    }
    s.finalize();
    return s;
}

std::unique_ptr<Lbvh> build_lbvh(const Scene& scene, const std::map<std::string, std::string>& params) {
    auto accel = make_accelerator("lbvh", params);
    auto* lbvh = dynamic_cast<Lbvh*>(accel.get());
    EXPECT_NE(lbvh, nullptr);
    accel.release();
    std::unique_ptr<Lbvh> out(lbvh);
    out->build(scene);
    return out;
}

std::string describe(const std::map<std::string, std::string>& params) {
    std::string s;
    for (const auto& [k, v] : params) s += (s.empty() ? "" : " ") + k + "=" + v;
    return s;
}

// Checks the tree against the split rule itself, from Morton codes recomputed here: the
// leaves are in code order (equal codes by primitive index), and every inner node over
// the slots [b, e) splits at m where it must — at the first code with the highest bit
// in which codes[b] and codes[e-1] differ, or in the middle when they are equal.
// (64-bit codes serve every width: spreading 10 bits gives the same value in both types.)
void expect_morton_splits(const Scene& scene, const FlatBvh& bvh, int bits) {
    const MortonQuantizer q(point_bounds(scene.centroids), bits);
    std::vector<uint64_t> codes;
    for (uint32_t id : bvh.prim_ids) codes.push_back(q.code<uint64_t>(scene.centroids[id]));
    for (size_t i = 1; i < codes.size(); ++i) {
        ASSERT_LE(codes[i - 1], codes[i]) << "slot " << i;
        if (codes[i - 1] == codes[i]) {
            ASSERT_LT(bvh.prim_ids[i - 1], bvh.prim_ids[i]) << "slot " << i;
        }
    }
    size_t checked = 0;
    // Returns the slot range of the subtree at `node`.
    auto walk = [&](auto&& self, uint32_t node) -> std::pair<uint32_t, uint32_t> {
        const BvhNode& n = bvh.nodes[node];
        if (n.is_leaf()) return {n.first_prim(), n.first_prim() + n.prim_count()};
        const auto [b, m] = self(self, node + 1);
        const auto [m2, e] = self(self, n.second_child());
        EXPECT_EQ(m, m2) << "children of node " << node << " are not adjacent";
        if (codes[b] == codes[e - 1]) {
            EXPECT_EQ(m, b + (e - b) / 2) << "node " << node;
        } else {
            const int bit = std::bit_width(codes[b] ^ codes[e - 1]) - 1;
            EXPECT_EQ(codes[m - 1] >> bit & 1, 0u) << "node " << node;
            EXPECT_EQ(codes[m] >> bit & 1, 1u) << "node " << node;
            EXPECT_EQ(n.axis(), bit % 3) << "node " << node;
        }
        ++checked;
        return {b, e};
    };
    if (!bvh.empty()) walk(walk, 0);
    EXPECT_EQ(checked, bvh.nodes.size() - (bvh.nodes.size() + 1) / 2);  // inner nodes
}

void expect_same_tree(const FlatBvh& a, const FlatBvh& b, const std::string& what) {
    ASSERT_EQ(a.nodes.size(), b.nodes.size()) << what;
    ASSERT_EQ(a.prim_ids, b.prim_ids) << what;
    EXPECT_EQ(a.depth, b.depth) << what;
    for (size_t i = 0; i < a.nodes.size(); ++i)
        ASSERT_EQ(std::memcmp(&a.nodes[i], &b.nodes[i], sizeof(BvhNode)), 0) << what << ": node " << i;
}

}  // namespace

TEST(Lbvh, AgreesWithEmbreeOnRandomSoups) {
    Scene scene = random_soup(3000, 42);
    const auto rays = test::probe_rays(scene, 3000);
    for (const char* bits : {"10", "21"})
        for (const char* max_prims : {"1", "4"})
            for (const char* traversal : {"ordered", "report"}) {
                const std::map<std::string, std::string> p{
                    {"bits", bits}, {"max_prims", max_prims}, {"traversal", traversal}};
                auto lbvh = build_lbvh(scene, p);
                test::expect_valid_bvh(lbvh->tree(), scene, /*tight=*/true, "lbvh");
                expect_morton_splits(scene, lbvh->tree(), std::stoi(bits));
                test::expect_agrees_with_embree(scene, *lbvh, rays, "lbvh soup " + describe(p));
            }
}

TEST(Lbvh, AgreesWithEmbreeOnHandMadeScenes) {
    Scene grid = grid_mesh(40, 30, false);
    Scene corners = cube_corners();
    for (const Scene* scene : {&grid, &corners})
        for (const char* bits : {"10", "21"})
            for (const char* traversal : {"ordered", "report"}) {
                const std::map<std::string, std::string> p{{"bits", bits}, {"traversal", traversal}};
                auto lbvh = build_lbvh(*scene, p);
                test::expect_valid_bvh(lbvh->tree(), *scene, /*tight=*/true, "lbvh");
                test::expect_agrees_with_embree(*scene, *lbvh, test::probe_rays(*scene, 2000),
                                                "lbvh " + scene->name + " " + describe(p));
            }
}

// Eight separated triangles, max_prims 1: a complete binary tree of 15 nodes whose levels
// split on the Morton bits from the top: z, then y, then x. The leaves come in Morton
// order, which for this numbering is the primitive order.
TEST(Lbvh, CubeCornersGiveTheMortonTree) {
    Scene scene = cube_corners();
    auto lbvh = build_lbvh(scene, {{"max_prims", "1"}});
    const FlatBvh& t = lbvh->tree();
    ASSERT_EQ(t.nodes.size(), 15u);
    EXPECT_EQ(t.depth, 3u);
    EXPECT_EQ(t.prim_ids, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5, 6, 7}));
    // Depth-first: root 0, z-halves at 1 and 8, y-quarters at 2, 5, 9, 12, leaves between.
    EXPECT_EQ(t.nodes[0].axis(), 2);
    EXPECT_EQ(t.nodes[0].second_child(), 8u);
    for (uint32_t y : {1u, 8u}) EXPECT_EQ(t.nodes[y].axis(), 1) << y;
    for (uint32_t x : {2u, 5u, 9u, 12u}) {
        EXPECT_FALSE(t.nodes[x].is_leaf());
        EXPECT_EQ(t.nodes[x].axis(), 0) << x;
        EXPECT_EQ(t.nodes[x].second_child(), x + 2);
    }
    const BuildStats s = lbvh->build_stats();
    EXPECT_EQ(s.nodes, 15u);
    EXPECT_EQ(s.leaves, 8u);
    EXPECT_EQ(s.max_depth, 3u);
    EXPECT_EQ(s.avg_leaf_size, 1.0);
    EXPECT_EQ(s.extra.at("equal_code_splits"), 0.0);
    ASSERT_TRUE(s.sah_cost.has_value());

    // max_prims 4: one split on z, two leaves of four; max_prims 8: the root is the leaf.
    auto four = build_lbvh(scene, {{"max_prims", "4"}});
    ASSERT_EQ(four->tree().nodes.size(), 3u);
    EXPECT_EQ(four->tree().nodes[0].axis(), 2);
    EXPECT_EQ(four->tree().nodes[1].prim_count(), 4u);
    EXPECT_EQ(build_lbvh(scene, {{"max_prims", "8"}})->tree().nodes.size(), 1u);
    // Coarse grids split the same cells: one bit per axis is enough for eight corners.
    EXPECT_EQ(build_lbvh(scene, {{"bits", "1"}})->tree().nodes.size(), 15u);
}

// The same tree whatever the thread count: subtrees built by other threads land where a
// one-thread depth-first build puts them.
TEST(Lbvh, TreeIsIdenticalForAnyThreadCount) {
    Scene scene = random_soup(20000, 9);
    for (const char* max_prims : {"1", "3"}) {
        auto one = build_lbvh(scene, {{"threads", "1"}, {"max_prims", max_prims}});
        EXPECT_EQ(one->build_stats().extra.at("build_tasks"), 0.0);
        for (const char* threads : {"2", "3", "7"}) {
            auto many = build_lbvh(scene, {{"threads", threads}, {"max_prims", max_prims}, {"task_threshold", "100"}});
            // The root's second child alone has thousands of primitives: at least one task.
            EXPECT_GT(many->build_stats().extra.at("build_tasks"), 0.0) << threads;
            expect_same_tree(one->tree(), many->tree(), std::string("threads=") + threads + " max_prims=" + max_prims);
        }
    }
    // A leaf forced at max_depth leaves a subtree short of its 2m - 1 nodes: the in-place
    // build of max_prims 1 on several threads starts again in pieces.
    auto shallow = build_lbvh(scene, {{"threads", "1"}, {"max_depth", "9"}});
    ASSERT_GT(shallow->build_stats().extra.at("forced_leaves"), 0.0);
    for (const char* threads : {"2", "7"})
        expect_same_tree(shallow->tree(), build_lbvh(scene, {{"threads", threads}, {"max_depth", "9"}})->tree(),
                         std::string("max_depth=9 threads=") + threads);
    auto tiny_tasks = build_lbvh(scene, {{"threads", "2"}, {"task_threshold", "1"}});
    expect_same_tree(build_lbvh(scene, {})->tree(), tiny_tasks->tree(), "task_threshold=1");
    test::expect_agrees_with_embree(scene, *tiny_tasks, test::probe_rays(scene, 1000), "lbvh threads=2");
}

// build_tasks is a property of the tree and the parameters, not of scheduling: on several
// threads every second child of more than task_threshold primitives is handed out as a task
// (on one thread none is). Counted here from the finished tree, for several thread counts
// and repeated builds (which, with a thread budget, once reported 1 or 2 tasks for threads=2
// depending on which thread finished first).
TEST(Lbvh, BuildTasksDoNotDependOnScheduling) {
    Scene scene = random_soup(5000, 4);
    // Primitives under each node of a depth-first tree (children after their parent).
    auto second_children_above = [](const FlatBvh& t, uint32_t threshold) {
        std::vector<uint32_t> prims(t.nodes.size());
        double above = 0;
        for (size_t i = t.nodes.size(); i-- > 0;) {
            const BvhNode& n = t.nodes[i];
            if (n.is_leaf()) {
                prims[i] = n.prim_count();
                continue;
            }
            prims[i] = prims[i + 1] + prims[n.second_child()];
            above += prims[n.second_child()] > threshold;
        }
        return above;
    };
    for (const char* threshold : {"10", "100"}) {
        auto one = build_lbvh(scene, {{"threads", "1"}, {"task_threshold", threshold}});
        EXPECT_EQ(one->build_stats().extra.at("build_tasks"), 0.0);
        const double expected = second_children_above(one->tree(), uint32_t(std::stoul(threshold)));
        ASSERT_GT(expected, 1.0) << threshold;
        for (const char* threads : {"2", "3", "7"})
            for (int repeat = 0; repeat < 20; ++repeat) {
                auto again = build_lbvh(scene, {{"threads", threads}, {"task_threshold", threshold}});
                ASSERT_EQ(again->build_stats().extra.at("build_tasks"), expected)
                    << "threads=" << threads << " task_threshold=" << threshold << " build " << repeat;
            }
    }
}

TEST(Lbvh, IdenticalTrianglesSplitInTheMiddle) {
    Scene scene;
    scene.name = "identical";
    for (int i = 0; i < 100; ++i) add_triangle(scene, {0, 0, 0}, {1, 0, 0}, {0, 1, 0.5f});
    scene.finalize();
    for (const char* bits : {"10", "21"}) {
        auto lbvh = build_lbvh(scene, {{"bits", bits}});
        // One code for all: every inner node is a middle split, 99 of them, and the tree
        // is balanced: 100 leaves at depth at most ceil(log2 100) = 7.
        EXPECT_EQ(lbvh->tree().nodes.size(), 199u);
        EXPECT_EQ(lbvh->tree().depth, 7u);
        EXPECT_EQ(lbvh->build_stats().extra.at("equal_code_splits"), 99.0);
        test::expect_valid_bvh(lbvh->tree(), scene, /*tight=*/true, "lbvh");
        test::expect_agrees_with_embree(scene, *lbvh, test::probe_rays(scene, 500),
                                        std::string("identical bits=") + bits);
    }
}

TEST(Lbvh, EqualCentroidsDifferentTriangles) {
    // Triangles of different shapes and orientations all centred on (1, 2, 3).
    Scene scene;
    scene.name = "equal-centroids";
    // Corners c + d, c - d and c + (d.x, -d.y, d.z) / 2 have a box symmetric about c;
    // d in multiples of 1/64 keeps every sum exact, so the centroids are exactly equal.
    SplitMix64 rng(5);
    const Vec3 c{1, 2, 3};
    for (int i = 0; i < 64; ++i) {
        auto coord = [&] { return float(int(rng.below(129)) - 64) / 64.0f; };
        const Vec3 d{coord(), coord(), coord()};
        add_triangle(scene, c + d, c - d, c + Vec3{d.x, -d.y, d.z} * 0.5f);
    }
    scene.finalize();
    for (size_t i = 1; i < scene.centroids.size(); ++i) ASSERT_EQ(scene.centroids[i], scene.centroids[0]);
    auto lbvh = build_lbvh(scene, {});
    EXPECT_EQ(lbvh->tree().nodes.size(), 127u);
    EXPECT_EQ(lbvh->tree().depth, 6u);
    EXPECT_EQ(lbvh->build_stats().extra.at("equal_code_splits"), 63.0);
    test::expect_agrees_with_embree(scene, *lbvh, test::probe_rays(scene, 1000), "equal centroids");
}

TEST(Lbvh, FlatSceneWithZeroExtentAxis) {
    Scene scene = grid_mesh(25, 25, true);  // every centroid has z = 0
    for (const char* bits : {"10", "21"}) {
        auto lbvh = build_lbvh(scene, {{"bits", bits}});
        test::expect_valid_bvh(lbvh->tree(), scene, /*tight=*/true, "lbvh");
        EXPECT_EQ(lbvh->tree().nodes.size(), 2 * scene.triangle_count() - 1);
        for (const BvhNode& n : lbvh->tree().nodes)
            if (!n.is_leaf()) {
                EXPECT_NE(n.axis(), 2);  // no split on the flat axis
            }
        test::expect_agrees_with_embree(scene, *lbvh, test::probe_rays(scene, 2000), std::string("flat bits=") + bits);
    }
}

TEST(Lbvh, SingleTriangleAndEmptyScene) {
    Scene one;
    add_triangle(one, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    one.finalize();
    auto lbvh = build_lbvh(one, {});
    ASSERT_EQ(lbvh->tree().nodes.size(), 1u);
    EXPECT_TRUE(lbvh->tree().nodes[0].is_leaf());
    EXPECT_EQ(lbvh->build_stats().leaves, 1u);
    test::expect_agrees_with_embree(one, *lbvh, test::probe_rays(one, 300), "single triangle");

    Scene empty;
    empty.finalize();
    auto none = build_lbvh(empty, {});
    EXPECT_TRUE(none->tree().empty());
    const BuildStats s = none->build_stats();
    EXPECT_EQ(s.nodes, 0u);
    EXPECT_FALSE(s.sah_cost.has_value());
    std::vector<Ray> rays{{{0, 0, -1}, 0, {0, 0, 1}, kInfinity}};
    std::vector<Hit> hits(1);
    std::vector<uint8_t> occluded(1, 1);
    none->closest_hits(rays, hits);
    none->any_hits(rays, occluded);
    EXPECT_FALSE(hits[0].found());
    EXPECT_EQ(occluded[0], 0);
}

TEST(Lbvh, DenseClusterWithFarOutlier) {
    // 2000 triangles in a unit box and one at 1e6: with 10 bits the whole cluster falls
    // into the first grid cell (cells are ~1000 wide), so only middle splits separate it;
    // with 21 bits the cells are ~0.5 wide and the codes still tell it apart.
    const Scene cluster = random_soup(2000, 77, 0.05f);  // rays aim here: the interesting hits
    Scene scene = cluster;
    scene.name = "cluster-outlier";
    add_triangle(scene, {1e6f, 1e6f, 1e6f}, {1e6f + 1, 1e6f, 1e6f}, {1e6f, 1e6f + 1, 1e6f});
    scene.finalize();
    const auto rays = test::probe_rays(cluster, 2000);
    for (const char* bits : {"10", "21"}) {
        auto lbvh = build_lbvh(scene, {{"bits", bits}});
        test::expect_valid_bvh(lbvh->tree(), scene, /*tight=*/true, "lbvh");
        expect_morton_splits(scene, lbvh->tree(), std::stoi(bits));
        EXPECT_EQ(lbvh->tree().nodes.size(), 2 * scene.triangle_count() - 1);
        const double equal_splits = lbvh->build_stats().extra.at("equal_code_splits");
        if (std::string(bits) == "10") {
            EXPECT_EQ(equal_splits, 1999.0);     // the whole cluster: 2000 leaves, 1999 splits
            EXPECT_EQ(lbvh->tree().depth, 12u);  // balanced below the root: 1 + ceil(log2 2000)
        }
        test::expect_agrees_with_embree(scene, *lbvh, rays, std::string("cluster+outlier bits=") + bits);
    }
}

TEST(Lbvh, MaxDepthMakesLeaves) {
    Scene scene = random_soup(1000, 3);
    const auto rays = test::probe_rays(scene, 1000);
    // Depth 0: the root is one leaf of everything; depth 1: root and two leaves.
    auto zero = build_lbvh(scene, {{"max_depth", "0"}});
    ASSERT_EQ(zero->tree().nodes.size(), 1u);
    EXPECT_EQ(zero->tree().nodes[0].prim_count(), 1000u);
    auto one = build_lbvh(scene, {{"max_depth", "1"}});
    ASSERT_EQ(one->tree().nodes.size(), 3u);
    EXPECT_EQ(one->tree().depth, 1u);
    EXPECT_EQ(one->build_stats().extra.at("forced_leaves"), 2.0);
    EXPECT_EQ(one->tree().nodes[1].prim_count() + one->tree().nodes[2].prim_count(), 1000u);
    for (const char* traversal : {"ordered", "report"})
        test::expect_agrees_with_embree(scene, *build_lbvh(scene, {{"max_depth", "1"}, {"traversal", traversal}}), rays,
                                        std::string("max_depth=1 ") + traversal);
    // Depth 200 never binds: the tree ends where the codes and max_prims end it.
    auto deep = build_lbvh(scene, {{"max_depth", "200"}});
    EXPECT_EQ(deep->tree().nodes.size(), 1999u);
    EXPECT_EQ(deep->build_stats().extra.at("forced_leaves"), 0.0);
    expect_same_tree(deep->tree(), build_lbvh(scene, {{"max_depth", "1000"}})->tree(), "max_depth 200 vs 1000");
    test::expect_agrees_with_embree(scene, *deep, rays, "max_depth=200");
}

TEST(Lbvh, AnyBitsFromOneToTwentyOne) {
    Scene scene = random_soup(2000, 11);
    const auto rays = test::probe_rays(scene, 1000);
    for (int bits : {1, 2, 5, 10, 11, 15, 21}) {
        auto lbvh = build_lbvh(scene, {{"bits", std::to_string(bits)}});
        test::expect_valid_bvh(lbvh->tree(), scene, /*tight=*/true, "lbvh");
        expect_morton_splits(scene, lbvh->tree(), bits);
        EXPECT_EQ(lbvh->build_stats().extra.at("morton_bits"), double(bits));
        test::expect_agrees_with_embree(scene, *lbvh, rays, "bits=" + std::to_string(bits));
    }
    // bits = 1: 8 cells for 2000 triangles, most splits are middle splits.
    EXPECT_GT(build_lbvh(scene, {{"bits", "1"}})->build_stats().extra.at("equal_code_splits"), 1000.0);
}

TEST(Lbvh, RefusesOutOfRangeParameters) {
    for (const char* bad : {"0", "22", "64"}) {
        try {
            make_accelerator("lbvh", {{"bits", bad}});
            FAIL() << "bits=" << bad << " accepted";
        } catch (const ParamError& e) {
            EXPECT_NE(std::string(e.what()).find("'bits'"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("[1, 21]"), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(make_accelerator("lbvh", {{"max_prims", "0"}}), ParamError);
    EXPECT_THROW(make_accelerator("lbvh", {{"traversal", "stackless"}}), ParamError);
    EXPECT_THROW(make_accelerator("lbvh", {{"task_threshold", "0"}}), ParamError);
}

TEST(Lbvh, StanfordBunnyAgreesWithEmbree) {
    const Scene scene = test::stanford_bunny();
    ASSERT_EQ(scene.triangle_count(), 69451u);
    const auto rays = test::probe_rays(scene, 20000, 11);
    for (const std::map<std::string, std::string>& p : std::vector<std::map<std::string, std::string>>{
             {}, {{"bits", "21"}, {"traversal", "report"}}, {{"max_prims", "4"}, {"threads", "2"}}}) {
        auto lbvh = build_lbvh(scene, p);
        test::expect_valid_bvh(lbvh->tree(), scene, /*tight=*/true, "lbvh bunny");
        expect_morton_splits(scene, lbvh->tree(), p.count("bits") ? 21 : 10);
        const BuildStats s = lbvh->build_stats();
        if (p.count("max_prims") == 0) {
            EXPECT_EQ(s.nodes.value(), 2u * 69451 - 1) << describe(p);  // one triangle per leaf
        }
        std::printf("[bunny] lbvh %s: nodes %llu, depth %llu, sah %.3f, equal-code splits %g\n", describe(p).c_str(),
                    (unsigned long long)s.nodes.value(), (unsigned long long)s.max_depth.value(), s.sah_cost.value(),
                    s.extra.at("equal_code_splits"));
        test::expect_agrees_with_embree(scene, *lbvh, rays, "lbvh bunny " + describe(p));
    }
}

// build=report (the report's Algorithm 2: boxes fitted top-down per node, the split by a
// linear scan) builds the very tree build=karras does: the node arrays byte for byte and
// the build counts, on the bunny and the three procedural scenes.
TEST(Lbvh, ReportBuildGivesTheKarrasTree) {
    const std::vector<Scene> scenes = {test::stanford_bunny(), make_procedural("forest", {}),
                                       make_procedural("city", {}), random_soup(20000, 3)};
    for (const Scene& scene : scenes)
        for (const char* max_prims : {"1", "4"}) {
            const std::string what = scene.name + " max_prims=" + max_prims;
            auto karras = build_lbvh(scene, {{"build", "karras"}, {"max_prims", max_prims}});
            auto report = build_lbvh(scene, {{"build", "report"}, {"max_prims", max_prims}});
            ASSERT_GT(karras->tree().nodes.size(), 1u) << what;
            expect_same_tree(karras->tree(), report->tree(), what);
            const BuildStats a = karras->build_stats(), b = report->build_stats();
            EXPECT_EQ(a.nodes, b.nodes) << what;
            EXPECT_EQ(a.leaves, b.leaves) << what;
            EXPECT_EQ(a.max_depth, b.max_depth) << what;
            EXPECT_EQ(a.extra, b.extra) << what;
        }
    // The default is karras, and the two names are the declared choices.
    const AcceleratorInfo info = Lbvh::info();
    const auto spec =
        std::find_if(info.params.begin(), info.params.end(), [](const ParamSpec& p) { return p.name == "build"; });
    ASSERT_NE(spec, info.params.end());
    EXPECT_EQ(spec->default_value, "karras");
    EXPECT_EQ(spec->choices, (std::vector<std::string>{"karras", "report", "median"}));
    EXPECT_THROW(make_accelerator("lbvh", {{"build", "binary"}}), ParamError);
}

// build=median (the LBVH the report's section 5.2 measured: Morton codes and a radix sort,
// then its BVH's median build) gives the median BVH's tree node for node, and still sorts:
// on the bunny and the three procedural scenes, at max_prims 1 and 4 and a max_depth that
// forces leaves.
TEST(Lbvh, MedianBuildGivesTheMedianBvhTree) {
    const std::vector<Scene> scenes = {test::stanford_bunny(), make_procedural("forest", {}),
                                       make_procedural("city", {}), random_soup(20000, 3)};
    for (const Scene& scene : scenes)
        for (const auto& [max_prims, max_depth] : {std::pair{"1", "50"}, {"4", "50"}, {"1", "8"}}) {
            const std::string what = scene.name + " max_prims=" + max_prims + " max_depth=" + max_depth;
            auto lbvh = build_lbvh(scene, {{"build", "median"}, {"max_prims", max_prims}, {"max_depth", max_depth}});
            auto accel = make_accelerator(
                "bvh",
                {{"split", "median"}, {"max_prims", max_prims}, {"max_depth", max_depth}, {"leaf_test", "scalar"}});
            const Bvh& bvh = static_cast<const Bvh&>(*accel);
            accel->build(scene);
            ASSERT_GT(bvh.tree().nodes.size(), 1u) << what;
            expect_same_tree(bvh.tree(), lbvh->tree(), what);
            const BuildStats a = bvh.build_stats(), b = lbvh->build_stats();
            EXPECT_EQ(a.nodes, b.nodes) << what;
            EXPECT_EQ(a.extra.at("forced_leaves"), b.extra.at("forced_leaves")) << what;
            EXPECT_EQ(a.extra.at("degenerate_splits"), b.extra.at("degenerate_splits")) << what;
            EXPECT_GT(b.extra.at("sort_passes"), 0.0) << what;  // the codes were sorted
        }
}
