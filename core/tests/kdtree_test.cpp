// The kd-tree: agreement with Embree, identical trees from both builders, hand-derived
// trees and counters, the depth rule, degenerate scenes and stiff parameters, the bunny.
#include "accelbench/accel/kdtree/kdtree.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "accelbench/base/random.h"
#include "accelbench/scene/mesh_io.h"
#include "accelbench/scene/procedural.h"
#include "agreement.h"
#include "test_scenes.h"

using namespace accelbench;

namespace {

// ---- scenes -------------------------------------------------------------------------

void add_triangle(Scene& s, Vec3 a, Vec3 b, Vec3 c) {
    const uint32_t i = uint32_t(s.vertices.size());
    s.vertices.insert(s.vertices.end(), {a, b, c});
    s.triangles.push_back({i, i + 1, i + 2});
}

// The project's random soup: equilateral triangles of edge `size` in the unit box.
Scene soup(int n, uint64_t seed, float size) {
    return make_procedural(
        "soup", {{"triangles", std::to_string(n)}, {"seed", std::to_string(seed)}, {"size", std::to_string(size)}});
}

Scene flattened(Scene s, int axis, float at) {
    for (auto& v : s.vertices) v[axis] = at;
    s.name += "-flat";
    s.finalize();
    return s;
}

// The faces of a k x k x k lattice of unit cubes, each unit square as two triangles:
// every triangle is axis-aligned and lies in a plane that is also a face of many other
// triangles' boxes, i.e. on candidate split planes. Centroids sit at thirds, away from
// every other edge.
Scene lattice(int k) {
    Scene s;
    s.name = "lattice";
    for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        for (int a = 0; a <= k; ++a)
            for (int i = 0; i < k; ++i)
                for (int j = 0; j < k; ++j) {
                    auto p = [&](int di, int dj) {
                        Vec3 q;
                        q[axis] = float(a);
                        q[u] = float(i + di);
                        q[v] = float(j + dj);
                        return q;
                    };
                    add_triangle(s, p(0, 0), p(1, 0), p(0, 1));
                    add_triangle(s, p(1, 1), p(0, 1), p(1, 0));
                }
    }
    s.finalize();
    return s;
}

std::unique_ptr<Accelerator> build_kdtree(const Scene& scene, std::map<std::string, std::string> params) {
    auto accel = make_accelerator("kdtree", params);
    accel->build(scene);
    return accel;
}

// The triangle's centroid (Scene::centroids holds bounding-box centres, which for a
// right triangle lie on its hypotenuse).
Vec3 centroid(const Scene& s, uint32_t p) { return (s.vertex(p, 0) + s.vertex(p, 1) + s.vertex(p, 2)) / 3.0f; }

const KdTree& as_kdtree(const Accelerator& a) { return dynamic_cast<const KdTree&>(a); }

std::string describe(const std::map<std::string, std::string>& params) {
    std::string s;
    for (const auto& [k, v] : params) s += (s.empty() ? "" : ",") + k + "=" + v;
    return s.empty() ? "defaults" : s;
}

const std::vector<std::map<std::string, std::string>> kParamSets = {
    {},
    {{"max_prims", "4"}},
    {{"max_prims", "0"}},
    {{"isect_cost", "5"}},  // pbrt-v4's default
    {{"empty_bonus", "0"}},
    {{"max_depth", "6"}},
    {{"max_depth", "40"}, {"traversal_cost", "0.1"}},
};

// Closest hit of one ray.
Hit trace(const Accelerator& a, const Ray& r, RayStats* stats = nullptr) {
    std::vector<Hit> hits(1);
    std::vector<RayStats> st(stats ? 1 : 0);
    a.closest_hits({&r, 1}, hits, st);
    if (stats) *stats = st[0];
    return hits[0];
}

}  // namespace

// ---- agreement with Embree -------------------------------------------------------------

TEST(KdTree, AgreesWithEmbreeOnRandomSoups) {
    for (uint64_t seed : {1u, 2u}) {
        // a sparse soup of small triangles, and a dense one where most boxes overlap
        const Scene scene = soup(seed == 1 ? 1000 : 2500, seed, seed == 1 ? 0.3f : 0.05f);
        const auto rays = test::probe_rays(scene, 3000, seed);
        for (const auto& base : kParamSets)
            for (const char* build : {"nlogn", "pbrt"}) {
                auto params = base;
                params["build"] = build;
                auto kd = build_kdtree(scene, params);
                test::expect_agrees_with_embree(scene, *kd, rays,
                                                "soup " + std::to_string(seed) + " " + describe(params));
            }
    }
}

TEST(KdTree, AgreesWithEmbreeOnLatticeAndFlatScenes) {
    const Scene flat = flattened(soup(1000, 5, 0.1f), 2, 0.5f);  // zero extent on z
    const Scene grid = lattice(4);
    for (const Scene* scene : {static_cast<const Scene*>(&flat), &grid})
        for (const auto& base : kParamSets) {
            auto kd = build_kdtree(*scene, base);
            test::expect_agrees_with_embree(*scene, *kd, test::probe_rays(*scene, 3000, 9),
                                            scene->name + " " + describe(base));
        }
}

// Rays along the axes (zero and -0.0 direction components), some starting exactly on
// split planes and some lying in them.
TEST(KdTree, AxisAlignedRaysWithSignedZeros) {
    const Scene grid = lattice(3);
    auto kd = build_kdtree(grid, {});
    std::vector<Ray> rays;
    SplitMix64 r(3);
    for (int i = 0; i < 2000; ++i) {
        Vec3 org{r.uniform(0, 3), r.uniform(0, 3), r.uniform(0, 3)};
        // a third start on a lattice plane (a split plane of the tree)
        if (i % 3 == 0) org[i % 2] = float(int(org[i % 2]));
        Vec3 dir{0.0f, 0.0f, 0.0f};
        const int axis = i % 3;
        dir[axis] = (i / 3) % 2 ? 1.0f : -1.0f;
        for (int a = 0; a < 3; ++a)
            if (a != axis && (i / 6) % 2) dir[a] = -0.0f;
        org[axis] = dir[axis] > 0 ? -1.0f : 4.0f;
        rays.push_back({org, 0.0f, dir, kInfinity});
    }
    test::expect_agrees_with_embree(grid, *kd, rays, "lattice axis rays");
    std::vector<Hit> hits(rays.size());
    kd->closest_hits(rays, hits);
    for (const Hit& h : hits) EXPECT_TRUE(std::isfinite(h.t) || !h.found());
}

// ---- the two builders agree --------------------------------------------------------------

TEST(KdTree, PbrtAndNlognBuildIdenticalTrees) {
    std::vector<Scene> scenes;
    scenes.push_back(soup(3000, 11, 0.05f));
    scenes.push_back(soup(1000, 12, 0.5f));
    scenes.push_back(lattice(5));
    scenes.push_back(flattened(soup(1000, 13, 0.1f), 1, 0.0f));
    for (const Scene& scene : scenes)
        for (const auto& base : kParamSets) {
            auto params = base;
            params["build"] = "pbrt";
            auto a = build_kdtree(scene, params);
            params["build"] = "nlogn";
            auto b = build_kdtree(scene, params);
            const KdTree &ta = as_kdtree(*a), &tb = as_kdtree(*b);
            const std::string what = scene.name + " " + describe(base);
            ASSERT_GT(ta.nodes().size(), 1u) << what;
            ASSERT_EQ(ta.nodes().size(), tb.nodes().size()) << what;
            EXPECT_EQ(std::memcmp(ta.nodes().data(), tb.nodes().data(), ta.nodes().size() * sizeof(KdNode)), 0) << what;
            ASSERT_EQ(ta.prim_indices().size(), tb.prim_indices().size()) << what;
            EXPECT_TRUE(std::equal(ta.prim_indices().begin(), ta.prim_indices().end(), tb.prim_indices().begin()))
                << what;
        }
}

// ---- exact trees on hand-built scenes ------------------------------------------------------

// Two triangles in z = 0, A with x in [0, 1] and B with x in [3, 4], both y in [0, 1].
// Root box 4 x 1 x 0, area 8. Candidates on x (longest): t=1 (A's end) and t=3 (B's
// start). At t=1: below 1x1 (area 2, p=1/4) holds A, above 3x1 (area 6, p=3/4) holds B:
// cost 1 + 80 (1/4 + 3/4) = 81; at t=3 the mirror, also 81: the first wins. Leaf cost
// 160 > 81, so the root splits at x=1, and both children hold one primitive: 3 nodes.
Scene two_triangles() {
    Scene s;
    s.name = "two";
    add_triangle(s, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    add_triangle(s, {3, 0, 0}, {4, 0, 0}, {3, 1, 0});
    s.finalize();
    return s;
}

TEST(KdTree, ExactTreeForTwoTriangles) {
    const Scene s = two_triangles();
    for (const char* build : {"nlogn", "pbrt"}) {
        auto kd = build_kdtree(s, {{"build", build}});
        const KdTree& t = as_kdtree(*kd);
        ASSERT_EQ(t.nodes().size(), 3u);
        EXPECT_FALSE(t.nodes()[0].is_leaf());
        EXPECT_EQ(t.nodes()[0].axis(), 0);
        EXPECT_EQ(t.nodes()[0].split(), 1.0f);
        EXPECT_EQ(t.nodes()[0].above_child(), 2u);
        EXPECT_EQ(t.nodes()[1], KdNode::leaf(1, 0));
        EXPECT_EQ(t.nodes()[2], KdNode::leaf(1, 1));
        EXPECT_TRUE(t.prim_indices().empty());
        const BuildStats st = kd->build_stats();
        EXPECT_EQ(st.nodes, 3u);
        EXPECT_EQ(st.leaves, 2u);
        EXPECT_EQ(st.max_depth, 1u);
        EXPECT_EQ(st.memory_bytes, 3 * 8 + 2 * 36u);  // 3 nodes, no index array, 2 triangle copies
        EXPECT_EQ(st.avg_leaf_size, 1.0);
        EXPECT_EQ(st.extra.at("prim_refs"), 2.0);
        EXPECT_EQ(st.extra.at("empty_leaves"), 0.0);
        EXPECT_EQ(st.extra.at("bad_refines"), 0.0);
        // SAH of the tree with every structure's constants (1, 1): 1 + (2/8 * 1 + 6/8 * 1) = 2;
        // with this build's C_T = 1, C_I = 80: 1 + 80 = 81.
        EXPECT_NEAR(*st.sah_cost, 2.0, 1e-9);
        EXPECT_NEAR(st.extra.at("sah_cost_build"), 81.0, 1e-9);
    }
}

// With max_prims = 0 the above child [1,4] (area 6) holding B still splits: at t=3 its
// below side is empty: cost 1 + 80 (1 - 0.5) (2/6 * 1) = 14.33 < 80. The empty leaf
// comes first, then B in [3,4], which has no candidate strictly inside on any axis.
TEST(KdTree, ExactTreeWithEmptyLeaf) {
    const Scene s = two_triangles();
    auto kd = build_kdtree(s, {{"max_prims", "0"}});
    const KdTree& t = as_kdtree(*kd);
    ASSERT_EQ(t.nodes().size(), 5u);
    EXPECT_EQ(t.nodes()[1], KdNode::leaf(1, 0));
    EXPECT_EQ(t.nodes()[2], KdNode::interior(0, 3.0f, 4));
    EXPECT_EQ(t.nodes()[3], KdNode::leaf(0, 0));
    EXPECT_EQ(t.nodes()[4], KdNode::leaf(1, 1));
    const BuildStats st = kd->build_stats();
    EXPECT_EQ(st.leaves, 3u);
    EXPECT_EQ(st.max_depth, 2u);
    EXPECT_EQ(st.extra.at("empty_leaves"), 1.0);
    EXPECT_NEAR(*st.avg_leaf_size, 2.0 / 3.0, 1e-12);
}

// A (x in [0,1]), B lying IN the plane x = 2, C (x in [3,4]); all span y, z in [0,1].
// Box areas are 2 (2 dx + 1); root dx = 4, area 18. Candidates on x: t=1: 1 below, 2
// above, cost 1 + 80 (6/18 + 2 * 14/18) = 152.1; t=2 with B below or above: 1 + 80 (2 *
// 10/18 + 10/18) = 134.3 either way, so the tie sends B below; t=3: 152.1. Split at 2.
// Below [0,2] (area 10) holds A and B; t=1 gives 1 + 80 (6/10 + 6/10) = 97 < 160, so it
// splits into A | B. Above holds C alone.
TEST(KdTree, ExactTreeWithPrimitiveInTheSplitPlane) {
    Scene s;
    s.name = "planar";
    add_triangle(s, {0, 0, 0}, {1, 0, 1}, {0, 1, 1});
    add_triangle(s, {2, 0, 0}, {2, 1, 0}, {2, 0, 1});
    add_triangle(s, {3, 1, 1}, {4, 0, 0}, {4, 1, 0});
    s.finalize();
    for (const char* build : {"nlogn", "pbrt"}) {
        auto kd = build_kdtree(s, {{"build", build}});
        const KdTree& t = as_kdtree(*kd);
        ASSERT_EQ(t.nodes().size(), 5u) << build;
        EXPECT_EQ(t.nodes()[0], KdNode::interior(0, 2.0f, 4));
        EXPECT_EQ(t.nodes()[1], KdNode::interior(0, 1.0f, 3));
        EXPECT_EQ(t.nodes()[2], KdNode::leaf(1, 0));
        EXPECT_EQ(t.nodes()[3], KdNode::leaf(1, 1));
        EXPECT_EQ(t.nodes()[4], KdNode::leaf(1, 2));
        // Rays at B's centroid from both sides (and along the plane's normal) find B.
        const Vec3 c = centroid(s, 1);
        for (Vec3 from : {Vec3{3.5f, 0.2f, 0.4f}, Vec3{0.5f, 0.6f, 0.1f}, Vec3{2.5f, c.y, c.z}, Vec3{1.5f, c.y, c.z}}) {
            const Hit h = trace(*kd, {from, 0.0f, c - from, kInfinity});
            EXPECT_EQ(h.prim, 1u) << build << " from " << from.x;
            EXPECT_NEAR(h.t, 1.0f, 1e-5f);
        }
    }
}

// The ray from above A straight down: root (x split at 1, t_split = +inf since the x
// component is +0) sends it below only, the leaf holds A, hit, and the stack is empty.
TEST(KdTree, ExactCountersOnTwoTriangles) {
    const Scene s = two_triangles();
    auto kd = build_kdtree(s, {});
    RayStats st;
    const Hit h = trace(*kd, {{0.25f, 0.25f, 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, kInfinity}, &st);
    EXPECT_EQ(h.prim, 0u);
    EXPECT_EQ(st.box_tests, 1u);
    EXPECT_EQ(st.node_visits, 2u);
    EXPECT_EQ(st.prim_tests, 1u);
    // Obliquely onto A: the flat root box clips the ray to [1, 1], the plane x = 1 is
    // crossed at t = 4/3 > 1, so again only the below leaf.
    RayStats st3;
    const Hit h3 = trace(*kd, {{-1.0f, 0.25f, 0.5f}, 0.0f, {1.5f, 0.0f, -0.5f}, kInfinity}, &st3);
    EXPECT_EQ(h3.prim, 0u);
    EXPECT_EQ(st3.node_visits, 2u);
    EXPECT_EQ(st3.prim_tests, 1u);
}

// A hit beyond the leaf's own t-range must not end the search. A (x in [0, 3]) is
// slanted so the x axis meets it at x = 2.5; B (x in [1.6, 2]) meets it at x = 1.8.
// Root box 3 x 1.5 x 2 (area 27): the split at x = 1.6 costs 1 + 80 (17.2/27 + 2 *
// 15.8/27) = 145.6, the one at x = 2 costs 158, a leaf 160; so the first leaf along +x
// holds A alone, found at x = 2.5, outside that leaf. Stopping there would answer A.
TEST(KdTree, HitBeyondTheLeafDoesNotEndTheSearch) {
    Scene s;
    s.name = "beyond";
    add_triangle(s, {0, -1, -1}, {0, -1, 1}, {3, 0.2f, 0});
    add_triangle(s, {1.6f, -0.5f, -0.5f}, {1.6f, -0.5f, 0.5f}, {2.0f, 0.5f, 0});
    s.finalize();
    for (const char* build : {"nlogn", "pbrt"}) {
        auto kd = build_kdtree(s, {{"build", build}});
        const KdTree& t = as_kdtree(*kd);
        ASSERT_FALSE(t.nodes()[0].is_leaf());
        EXPECT_EQ(t.nodes()[0].axis(), 0);
        EXPECT_EQ(t.nodes()[0].split(), 1.6f);
        EXPECT_EQ(t.nodes()[1], KdNode::leaf(1, 0));
        RayStats st;
        const Hit h = trace(*kd, {{-1, 0, 0}, 0.0f, {1, 0, 0}, kInfinity}, &st);
        EXPECT_EQ(h.prim, 1u) << build;
        EXPECT_NEAR(h.t, 2.8f, 1e-5f);
        EXPECT_GE(st.prim_tests, 2u);
    }
}

// ---- the depth rule --------------------------------------------------------------------

TEST(KdTree, DefaultMaxDepth) {
    EXPECT_EQ(KdTree::default_max_depth(69451), 29);  // the bunny's triangles
    EXPECT_EQ(KdTree::default_max_depth(35947), 28);  // its vertices: the report's N, its "depth = 28"
    EXPECT_EQ(KdTree::default_max_depth(0), 8);
    EXPECT_EQ(KdTree::default_max_depth(1), 8);
    EXPECT_EQ(KdTree::default_max_depth(2), 9);        // 8 + 1.3
    EXPECT_EQ(KdTree::default_max_depth(1024), 21);    // 8 + 13
    EXPECT_EQ(KdTree::default_max_depth(871414), 34);  // 8 + 1.3 * 19.73 = 33.65
    const Scene s = soup(69451, 3, 0.01f);
    auto kd = build_kdtree(s, {});
    EXPECT_EQ(kd->build_stats().extra.at("max_depth_limit"), 29.0);
    EXPECT_LE(*kd->build_stats().max_depth, 29u);
    auto deep = build_kdtree(s, {{"max_depth", "12"}});
    EXPECT_EQ(deep->build_stats().extra.at("max_depth_limit"), 12.0);
    EXPECT_EQ(*deep->build_stats().max_depth, 12u);
}

// ---- degenerate inputs -------------------------------------------------------------------

TEST(KdTree, EmptySceneAndSingleTriangle) {
    Scene empty;
    empty.name = "empty";
    empty.finalize();
    auto kd = build_kdtree(empty, {});
    EXPECT_EQ(kd->build_stats().nodes, 0u);
    EXPECT_FALSE(trace(*kd, {{0, 0, 0}, 0.0f, {0, 0, 1}, kInfinity}).found());
    std::vector<Ray> r{{{0, 0, 0}, 0.0f, {0, 0, 1}, kInfinity}};
    std::vector<uint8_t> occ(1);
    kd->any_hits(r, occ);
    EXPECT_EQ(occ[0], 0);

    Scene one;
    one.name = "one";
    add_triangle(one, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    one.finalize();
    auto kd1 = build_kdtree(one, {{"max_prims", "0"}});
    EXPECT_EQ(kd1->build_stats().nodes, 1u);  // a flat box with no candidate inside
    const Hit h = trace(*kd1, {{0.2f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}, kInfinity});
    EXPECT_EQ(h.prim, 0u);
    EXPECT_EQ(h.t, 1.0f);
}

TEST(KdTree, IdenticalTrianglesMakeOneLeaf) {
    Scene s;
    s.name = "identical";
    for (int i = 0; i < 200; ++i) add_triangle(s, {0, 0, 0}, {1, 0.5f, 0}, {0.3f, 1, 1});
    s.finalize();
    auto kd = build_kdtree(s, {});
    const BuildStats st = kd->build_stats();
    EXPECT_EQ(st.nodes, 1u);  // no bounding-box face lies strictly inside the box
    EXPECT_EQ(st.extra.at("prim_refs"), 200.0);
    // Every copy is hit at the same distance, so which one is reported is arbitrary: only
    // hit/miss and occlusion must agree.
    const test::Agreement a = test::compare_with_embree(s, *kd, test::probe_rays(s, 500));
    EXPECT_EQ(a.mismatched_hit, 0u);
    EXPECT_EQ(a.mismatched_occlusion, 0u);
}

TEST(KdTree, EqualCentroidsTerminate) {
    // Triangles of very different sizes and orientations around one common centroid.
    Scene s;
    s.name = "centroids";
    SplitMix64 r(8);
    for (int i = 0; i < 500; ++i) {
        const float k = r.uniform(0.01f, 1.0f);
        const Vec3 a = r.unit_vector(), b = r.unit_vector();
        add_triangle(s, a * k, b * k, -(a + b) * k);
    }
    s.finalize();
    for (const char* build : {"nlogn", "pbrt"}) {
        auto kd = build_kdtree(s, {{"build", build}});
        EXPECT_LE(*kd->build_stats().max_depth, uint64_t(KdTree::default_max_depth(500)));
        test::expect_agrees_with_embree(s, *kd, test::probe_rays(s, 2000), std::string("centroids ") + build);
    }
}

// Every triangle of the lattice lies on planes the SAH considers; a ray aimed at each
// triangle's centroid from inside its cell (nothing can be in between) must return it.
TEST(KdTree, CoplanarTrianglesOnSplitPlanesAreFound) {
    const Scene grid = lattice(4);
    for (const auto& base : kParamSets)
        for (const char* build : {"nlogn", "pbrt"}) {
            auto params = base;
            params["build"] = build;
            auto kd = build_kdtree(grid, params);
            std::vector<Ray> rays;
            std::vector<uint32_t> want;
            SplitMix64 r(21);
            for (uint32_t p = 0; p < grid.triangle_count(); ++p) {
                const Vec3 n =
                    normalize(cross(grid.vertex(p, 1) - grid.vertex(p, 0), grid.vertex(p, 2) - grid.vertex(p, 0)));
                for (float side : {1.0f, -1.0f}) {
                    const Vec3 c = centroid(grid, p);
                    // an oblique and an exactly perpendicular ray (two zero components)
                    const Vec3 oblique = r.unit_vector() * 0.1f;
                    for (Vec3 off : {n * (0.4f * side) + oblique, n * (0.4f * side)}) {
                        rays.push_back({c + off, 0.0f, -off, kInfinity});
                        want.push_back(p);
                    }
                }
            }
            std::vector<Hit> hits(rays.size());
            kd->closest_hits(rays, hits);
            size_t wrong = 0;
            for (size_t i = 0; i < rays.size(); ++i) wrong += hits[i].prim != want[i];
            EXPECT_EQ(wrong, 0u) << build << " " << describe(base);
        }
}

// ---- stiff parameters ----------------------------------------------------------------------

TEST(KdTree, StiffParametersTerminateOrAreRefused) {
    // A dense cluster: 2000 heavily overlapping triangles shrunk into a box of side
    // 0.01, plus a few far away.
    Scene cluster = soup(2000, 31, 0.4f);
    for (auto& v : cluster.vertices) v = v * 0.01f;
    for (int i = 0; i < 20; ++i) add_triangle(cluster, {float(i), 5, 0}, {float(i) + 0.5f, 5, 0}, {float(i), 6, 1});
    cluster.finalize();
    const std::vector<std::map<std::string, std::string>> stiff = {
        {{"max_depth", "100"}, {"max_prims", "1"}},          {{"isect_cost", "10000"}, {"traversal_cost", "1"}},
        {{"isect_cost", "0.0001"}, {"traversal_cost", "1"}}, {{"isect_cost", "80"}, {"traversal_cost", "0.0001"}},
        {{"isect_cost", "80"}, {"traversal_cost", "10000"}}, {{"empty_bonus", "0.99"}},
        {{"empty_bonus", "1"}, {"max_depth", "100"}},
    };
    for (const auto& params : stiff) {
        auto kd = build_kdtree(cluster, params);
        const BuildStats st = kd->build_stats();
        std::printf("[stiff] %s: %llu nodes, %.0f refs, depth %llu\n", describe(params).c_str(),
                    (unsigned long long)*st.nodes, st.extra.at("prim_refs"), (unsigned long long)*st.max_depth);
        EXPECT_LE(st.extra.at("prim_refs"), double(KdTree::kMaxRefsPerPrim * cluster.triangle_count()));
        EXPECT_LE(*st.max_depth, uint64_t(KdTree::kMaxDepthLimit));
        test::expect_agrees_with_embree(cluster, *kd, test::probe_rays(cluster, 1000), describe(params));
    }
    // Out-of-range values are refused before anything is built, naming the range.
    try {
        make_accelerator("kdtree", {{"max_depth", "129"}});
        FAIL() << "max_depth 129 accepted";
    } catch (const ParamError& e) {
        EXPECT_NE(std::string(e.what()).find("out of range [0, 128]"), std::string::npos) << e.what();
    }
    EXPECT_THROW(make_accelerator("kdtree", {{"isect_cost", "0"}}), ParamError);
    EXPECT_THROW(make_accelerator("kdtree", {{"empty_bonus", "1.5"}}), ParamError);
    EXPECT_THROW(make_accelerator("kdtree", {{"build", "sah"}}), ParamError);
}

// ---- counters and any-hit -------------------------------------------------------------------

TEST(KdTree, CountersAreConsistent) {
    const Scene s = soup(2000, 41, 0.05f);
    auto kd = build_kdtree(s, {});
    const auto rays = test::probe_rays(s, 500);
    std::vector<Hit> a(rays.size()), b(rays.size());
    std::vector<RayStats> st(rays.size());
    kd->closest_hits(rays, a);
    kd->closest_hits(rays, b, st);
    for (size_t i = 0; i < rays.size(); ++i) {
        EXPECT_EQ(a[i].prim, b[i].prim);
        EXPECT_EQ(st[i].box_tests, 1u);
        if (b[i].found()) {
            EXPECT_GE(st[i].prim_tests, 1u);
            EXPECT_GE(st[i].node_visits, 1u);
        }
    }
}

// The mailbox (mailbox=true) tests a triangle once per ray: on every ray the same
// closest hit (primitive, distance, barycentrics) and occlusion answer as without it, at
// most as many triangle tests, the same traversal; and where triangles straddle split
// planes (the soup, the bunny) strictly fewer tests in all. (The lattice's triangles lie
// in or end on the integer planes its tree splits at: no reference is repeated there.)
TEST(KdTree, MailboxKeepsEveryAnswerWithFewerTests) {
    const Scene dense = soup(2500, 2, 0.05f);
    const Scene grid = lattice(4);
    const Scene bunny = test::stanford_bunny();
    for (const Scene* scene : {&dense, &grid, &bunny}) {
        const bool straddles = scene != &grid;
        const auto rays = test::probe_rays(*scene, 3000, 17);
        auto plain = build_kdtree(*scene, {});
        auto boxed = build_kdtree(*scene, {{"mailbox", "true"}});
        test::expect_agrees_with_embree(*scene, *boxed, rays, scene->name + " mailbox");
        std::vector<Hit> a(rays.size()), b(rays.size());
        std::vector<RayStats> sa(rays.size()), sb(rays.size());
        plain->closest_hits(rays, a, sa);
        boxed->closest_hits(rays, b, sb);
        uint64_t tests_plain = 0, tests_boxed = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            EXPECT_EQ(a[i].prim, b[i].prim) << scene->name << " ray " << i;
            EXPECT_EQ(a[i].t, b[i].t) << scene->name << " ray " << i;
            EXPECT_EQ(a[i].u, b[i].u) << scene->name << " ray " << i;
            EXPECT_EQ(sa[i].node_visits, sb[i].node_visits) << scene->name << " ray " << i;
            EXPECT_LE(sb[i].prim_tests, sa[i].prim_tests) << scene->name << " ray " << i;
            tests_plain += sa[i].prim_tests;
            tests_boxed += sb[i].prim_tests;
        }
        if (straddles) {
            EXPECT_LT(tests_boxed, tests_plain) << scene->name;
        }
        const std::vector<Ray> shadows = test::shadow_rays(*scene, rays, a);
        std::vector<uint8_t> oa(shadows.size()), ob(shadows.size());
        plain->any_hits(shadows, oa);
        boxed->any_hits(shadows, ob);
        EXPECT_EQ(oa, ob) << scene->name;
        std::printf("[mailbox] %s: %llu -> %llu triangle tests on %zu rays\n", scene->name.c_str(),
                    (unsigned long long)tests_plain, (unsigned long long)tests_boxed, rays.size());
    }
}

// ---- the memory bound ------------------------------------------------------------------------

// Long slivers along the three axes, crossing each other (a haystack): every split plane
// cuts a third of them, so references multiply with depth. With a budget below what the
// tree needs the build stops with an error naming the limit, and leaves an empty tree.
TEST(KdTree, ReferenceBudgetStopsTheBuildWithAClearMessage) {
    Scene hay;
    hay.name = "haystack";
    SplitMix64 r(3);
    for (int i = 0; i < 3000; ++i) {
        const int axis = i % 3;
        Vec3 p{r.uniform(), r.uniform(), r.uniform()};
        Vec3 q = p, w = p;
        p[axis] = 0.0f;
        q[axis] = 1.0f;
        w[axis] = 0.5f;
        w[(axis + 1) % 3] += 1e-3f;
        add_triangle(hay, p, q, w);
    }
    hay.finalize();
    KdTree full(KdTree::Config{});
    full.build(hay);
    const double refs = full.build_stats().extra.at("prim_refs");
    std::printf("[haystack] default tree: %.0f references (%.1f per triangle)\n", refs, refs / 3000);
    ASSERT_GT(refs, 100000.0);

    KdTree::Config tight;
    tight.max_refs = 100000;
    KdTree kd(tight);
    try {
        kd.build(hay);
        FAIL() << "the build ignored its reference budget";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("limit of 100000 primitive references"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(kd.nodes().empty());
    EXPECT_FALSE(trace(kd, {{0.5f, 0.5f, -1.0f}, 0.0f, {0, 0, 1}, kInfinity}).found());
}

// ---- real and procedural models -----------------------------------------------------------------

TEST(KdTree, AgreesWithEmbreeOnAProceduralForest) {
    const Scene forest = make_procedural("forest", {{"triangles", "20000"}, {"seed", "4"}});
    auto kd = build_kdtree(forest, {});
    test::expect_agrees_with_embree(forest, *kd, test::probe_rays(forest, 5000, 4), "forest 20k");
}

// The Stanford bunny (69,451 triangles; ../shared/models): both builders give the same
// tree, and probe rays agree with Embree. The report's kd-tree had 418,661 nodes and
// 128,943 intersection tests on it (Tables 2 and 4); ours differs (see the report to the
// team) and is printed, not asserted.
TEST(KdTree, StanfordBunny) {
    const Scene bunny = test::stanford_bunny();
    ASSERT_EQ(bunny.triangle_count(), 69451u);
    auto kd = build_kdtree(bunny, {});
    auto pbrt = build_kdtree(bunny, {{"build", "pbrt"}});
    const KdTree &a = as_kdtree(*kd), &b = as_kdtree(*pbrt);
    ASSERT_EQ(a.nodes().size(), b.nodes().size());
    EXPECT_EQ(std::memcmp(a.nodes().data(), b.nodes().data(), a.nodes().size() * sizeof(KdNode)), 0);
    EXPECT_TRUE(
        std::equal(a.prim_indices().begin(), a.prim_indices().end(), b.prim_indices().begin(), b.prim_indices().end()));
    const BuildStats st = kd->build_stats();
    std::printf(
        "[bunny] nodes %llu, leaves %llu, max depth %llu (limit %.0f), refs %.0f, empty leaves %.0f, "
        "bad refines %.0f, SAH %.1f, %.1f MB\n",
        (unsigned long long)*st.nodes, (unsigned long long)*st.leaves, (unsigned long long)*st.max_depth,
        st.extra.at("max_depth_limit"), st.extra.at("prim_refs"), st.extra.at("empty_leaves"),
        st.extra.at("bad_refines"), *st.sah_cost, double(*st.memory_bytes) / 1e6);
    EXPECT_EQ(st.extra.at("max_depth_limit"), 29.0);
    test::expect_agrees_with_embree(bunny, *kd, test::probe_rays(bunny, 20000, 7), "bunny", 0, 2);
}
