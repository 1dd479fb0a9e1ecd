// The shared BVH layer on a tree built by hand: node layout, finalize(), metrics and the
// two traversals with their exact counts.
#include <gtest/gtest.h>

#include "accelbench/accel/bvh/bvh_metrics.h"
#include "accelbench/accel/bvh/bvh_traversal.h"
#include "accelbench/accel/bvh/flat_bvh.h"

using namespace accelbench;

namespace {

// Four unit right triangles in the plane z = 0, triangle i covering [2i, 2i+1] x [0, 1],
// under the tree  root -> (A -> tri0, tri1), (B -> tri2, tri3), laid out depth-first:
//   0 root, 1 A, 2 leaf tri0, 3 leaf tri1, 4 B, 5 leaf tri2, 6 leaf tri3.
struct HandTree {
    Scene scene;
    FlatBvh bvh;
    HandTree() {
        for (uint32_t i = 0; i < 4; ++i) {
            const float x = 2.0f * float(i);
            scene.vertices.push_back({x, 0, 0});
            scene.vertices.push_back({x + 1, 0, 0});
            scene.vertices.push_back({x, 1, 0});
            scene.triangles.push_back({3 * i, 3 * i + 1, 3 * i + 2});
        }
        scene.finalize();
        auto box = [](float x0, float x1) { return Bounds3{{x0, 0, 0}, {x1, 1, 0}}; };
        bvh.nodes = {BvhNode::inner(box(0, 7), 4, 0), BvhNode::inner(box(0, 3), 3, 0), BvhNode::leaf(box(0, 1), 0, 1),
                     BvhNode::leaf(box(2, 3), 1, 1),  BvhNode::inner(box(4, 7), 6, 0), BvhNode::leaf(box(4, 5), 2, 1),
                     BvhNode::leaf(box(6, 7), 3, 1)};
        bvh.prim_ids = {0, 1, 2, 3};
        bvh.finalize(scene);
    }
};

Ray down_at(float x, float y) { return {{x, y, 1}, 0.0f, {0, 0, -1}, kInfinity}; }

}  // namespace

TEST(BvhNode, PacksCountAndAxis) {
    const BvhNode leaf = BvhNode::leaf({}, 17, BvhNode::kMaxLeafPrims);
    EXPECT_TRUE(leaf.is_leaf());
    EXPECT_EQ(leaf.first_prim(), 17u);
    EXPECT_EQ(leaf.prim_count(), BvhNode::kMaxLeafPrims);
    for (int axis = 0; axis < 3; ++axis) {
        const BvhNode inner = BvhNode::inner({}, 5, axis);
        EXPECT_FALSE(inner.is_leaf());
        EXPECT_EQ(inner.second_child(), 5u);
        EXPECT_EQ(inner.axis(), axis);
    }
}

TEST(FlatBvh, FinalizeCopiesTrianglesAndMeasuresDepth) {
    HandTree t;
    EXPECT_EQ(t.bvh.depth, 2u);
    ASSERT_EQ(t.bvh.triangles.size(), 4u);
    EXPECT_EQ(t.bvh.triangles[3].p0, (Vec3{6, 0, 0}));
    EXPECT_EQ(t.bvh.triangles[3].p2, (Vec3{6, 1, 0}));

    FlatBvh broken = t.bvh;
    broken.nodes[0] = BvhNode::inner(broken.nodes[0].bounds, 9, 0);  // second child out of range
    EXPECT_THROW(broken.finalize(t.scene), std::logic_error);
}

TEST(BvhMetrics, CountsAndSahCostByHand) {
    HandTree t;
    const BuildStats m = measure_bvh(t.bvh);
    EXPECT_EQ(m.nodes, 7u);
    EXPECT_EQ(m.leaves, 4u);
    EXPECT_EQ(m.max_depth, 2u);
    ASSERT_TRUE(m.avg_leaf_size.has_value());
    EXPECT_DOUBLE_EQ(*m.avg_leaf_size, 1.0);
    EXPECT_EQ(m.memory_bytes, 7u * 32 + 4u * 4 + 4u * 36);
    // Flat boxes: area 2 * dx * dy. Inner: root 14, A 6, B 6; leaves 2 each with 1 prim.
    ASSERT_TRUE(m.sah_cost.has_value());
    EXPECT_DOUBLE_EQ(*m.sah_cost, (14.0 + 6.0 + 6.0 + 4 * 2.0) / 14.0);

    FlatBvh empty;
    const BuildStats e = measure_bvh(empty);
    EXPECT_EQ(e.nodes, 0u);
    EXPECT_FALSE(e.sah_cost.has_value());
    EXPECT_FALSE(e.avg_leaf_size.has_value());
}

TEST(BvhTraversal, OrderedCountsOnHandTree) {
    HandTree t;
    Hit hit;
    RayStats s;
    intersect_bvh(BvhTraversal::ordered, t.bvh, down_at(6.25f, 0.25f), hit, s);
    EXPECT_EQ(hit.prim, 3u);
    EXPECT_FLOAT_EQ(hit.t, 1.0f);
    EXPECT_FLOAT_EQ(hit.u, 0.25f);
    EXPECT_FLOAT_EQ(hit.v, 0.25f);
    // root box; at root: A, B; at B: leaf tri2, leaf tri3; then one triangle.
    EXPECT_EQ(s.box_tests, 5u);
    EXPECT_EQ(s.node_visits, 3u);
    EXPECT_EQ(s.prim_tests, 1u);

    RayStats miss;
    Hit none;
    intersect_bvh(BvhTraversal::ordered, t.bvh, down_at(3.5f, 0.5f), none, miss);
    EXPECT_FALSE(none.found());
    EXPECT_EQ(miss.box_tests, 3u);
    EXPECT_EQ(miss.node_visits, 1u);
    EXPECT_EQ(miss.prim_tests, 0u);

    RayStats any;
    EXPECT_TRUE(occluded_bvh(BvhTraversal::ordered, t.bvh, down_at(0.25f, 0.25f), any));
    EXPECT_EQ(any.prim_tests, 1u);
    EXPECT_FALSE(occluded_bvh(BvhTraversal::ordered, t.bvh, down_at(3.5f, 0.5f), any));
}

TEST(BvhTraversal, ReportAlgorithmVisitsEveryHitBox) {
    HandTree t;
    Hit hit;
    RayStats s;
    intersect_bvh(BvhTraversal::report, t.bvh, down_at(6.25f, 0.25f), hit, s);
    EXPECT_EQ(hit.prim, 3u);
    // root, A (miss), B, leaf tri2 (miss), leaf tri3: each visited node is one box test.
    EXPECT_EQ(s.node_visits, 5u);
    EXPECT_EQ(s.box_tests, 5u);
    EXPECT_EQ(s.prim_tests, 1u);

    RayStats any;
    EXPECT_TRUE(occluded_bvh(BvhTraversal::report, t.bvh, down_at(2.25f, 0.5f), any));
    EXPECT_EQ(any.prim_tests, 1u);
}

TEST(BvhTraversal, NearChildFirstAndCulledByClosestHit) {
    // Two stacked triangles covering the same square at z = 0 and z = -1, each its own
    // leaf, the far one stored first: ordered traversal must enter the near one first and
    // then skip the far one (its entry distance lies beyond the hit).
    Scene scene;
    scene.vertices = {{0, 0, -1}, {1, 0, -1}, {0, 1, -1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    scene.triangles = {{0, 1, 2}, {3, 4, 5}};
    scene.finalize();
    FlatBvh bvh;
    bvh.nodes = {BvhNode::inner(scene.bounds, 2, 2), BvhNode::leaf(scene.prim_bounds[0], 0, 1),
                 BvhNode::leaf(scene.prim_bounds[1], 1, 1)};
    bvh.prim_ids = {0, 1};
    bvh.finalize(scene);
    Hit hit;
    RayStats s;
    intersect_bvh(BvhTraversal::ordered, bvh, down_at(0.25f, 0.25f), hit, s);
    EXPECT_EQ(hit.prim, 1u);
    EXPECT_EQ(s.prim_tests, 1u);
    EXPECT_EQ(s.node_visits, 2u);

    Hit hit_report;
    RayStats r;
    intersect_bvh(BvhTraversal::report, bvh, down_at(0.25f, 0.25f), hit_report, r);
    EXPECT_EQ(hit_report.prim, 1u);
    EXPECT_EQ(r.prim_tests, 2u);  // Algorithm 1 collects both
}

TEST(BvhTraversal, EmptyTreeMisses) {
    FlatBvh empty;
    Hit hit;
    RayStats s;
    intersect_bvh(BvhTraversal::ordered, empty, down_at(0, 0), hit, s);
    intersect_bvh(BvhTraversal::report, empty, down_at(0, 0), hit, s);
    EXPECT_FALSE(hit.found());
    EXPECT_FALSE(occluded_bvh(BvhTraversal::ordered, empty, down_at(0, 0), s));
    EXPECT_FALSE(occluded_bvh(BvhTraversal::report, empty, down_at(0, 0), s));
    EXPECT_EQ(s.node_visits + s.box_tests + s.prim_tests, 0u);
}

TEST(BvhTraversal, StackGrowsForDeepTrees) {
    // A caterpillar of 100 triangles along x, depth 99: deeper than the inline stack.
    Scene scene;
    const uint32_t n = 100;
    for (uint32_t i = 0; i < n; ++i) {
        const float x = float(i);
        scene.vertices.insert(scene.vertices.end(), {{x, 0, 0}, {x + 0.5f, 0, 0}, {x, 0.5f, 0}});
        scene.triangles.push_back({3 * i, 3 * i + 1, 3 * i + 2});
    }
    scene.finalize();
    // Inner node k (index 2k) holds triangles k..n-1: its first child (index 2k+1) is
    // the leaf of triangle k, its second child (index 2k+2) the inner node of the rest.
    FlatBvh bvh;
    for (uint32_t k = 0; k + 1 < n; ++k) {
        Bounds3 rest;
        for (uint32_t j = k; j < n; ++j) rest.extend(scene.prim_bounds[j]);
        bvh.nodes.push_back(BvhNode::inner(rest, 2 * k + 2, 0));
        bvh.nodes.push_back(BvhNode::leaf(scene.prim_bounds[k], k, 1));
    }
    bvh.nodes.push_back(BvhNode::leaf(scene.prim_bounds[n - 1], n - 1, 1));
    for (uint32_t i = 0; i < n; ++i) bvh.prim_ids.push_back(i);
    bvh.finalize(scene);
    EXPECT_EQ(bvh.depth, n - 1);
    // Rays down onto the first triangle (near the root) and the last one (at depth 99).
    for (uint32_t target : {0u, n - 1}) {
        Hit hit;
        NoCounters none;
        intersect_bvh(BvhTraversal::ordered, bvh, down_at(float(target) + 0.1f, 0.1f), hit, none);
        EXPECT_EQ(hit.prim, target);
        Hit hit_report;
        intersect_bvh(BvhTraversal::report, bvh, down_at(float(target) + 0.1f, 0.1f), hit_report, none);
        EXPECT_EQ(hit_report.prim, target);
    }
}
