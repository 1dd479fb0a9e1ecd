// The top-down BVH: agreement with Embree for every parameter combination, exact trees
// on hand-made scenes, and termination on degenerate input.
#include "accelbench/accel/bvh/bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "accelbench/accel/bvh/bvh_metrics.h"
#include "accelbench/accel/bvh/bvh_top_down.h"
#include "agreement.h"
#include "bvh_check.h"
#include "test_scenes.h"

using namespace accelbench;
using namespace accelbench::test;

namespace {

const std::vector<std::string> kSplits = {"median", "midpoint", "mean", "spatial_median", "sah"};

std::unique_ptr<Bvh> make_bvh(const std::map<std::string, std::string>& params) {
    auto accel = make_accelerator("bvh", params);
    return std::unique_ptr<Bvh>(static_cast<Bvh*>(accel.release()));
}

std::unique_ptr<Bvh> built(const Scene& scene, const std::map<std::string, std::string>& params) {
    auto bvh = make_bvh(params);
    bvh->build(scene);
    const BvhPacketLeaves* packets = bvh->packet_leaves();
    expect_valid_bvh(bvh->tree(), scene, /*tight=*/true, "bvh", /*copies=*/packets == nullptr);
    if (packets) expect_valid_packets(*packets, bvh->tree(), scene, "bvh packets");
    return bvh;
}

std::string describe(const std::map<std::string, std::string>& params) {
    std::string s = "bvh";
    for (const auto& [k, v] : params) s += " " + k + "=" + v;
    return s;
}

struct Shape {
    uint64_t nodes, leaves, depth;
};

void expect_shape(const Bvh& bvh, Shape want, const std::string& what) {
    const BuildStats s = bvh.build_stats();
    EXPECT_EQ(s.nodes.value(), want.nodes) << what;
    EXPECT_EQ(s.leaves.value(), want.leaves) << what;
    EXPECT_EQ(s.max_depth.value(), want.depth) << what;
}

double extra(const Bvh& bvh, const std::string& key) { return bvh.build_stats().extra.at(key); }

// Triangles whose boxes all have the centre (0, 0, 0) but different shapes and sizes.
Scene common_centroid_scene(int n) {
    Scene s;
    s.name = "test-common-centroid";
    TestRandom r(5);
    for (int i = 0; i < n; ++i) {
        const float a = 0.1f + r.next(), b = 0.1f + r.next(), c = r.next();
        add_triangle(s, {-a, -b, -c}, {a, -b, c}, {0, b, 0});
    }
    s.finalize();
    return s;
}

}  // namespace

// ---- agreement with Embree -----------------------------------------------------------

TEST(Bvh, EveryVariantAgreesWithEmbreeOnRandomSoup) {
    const Scene scene = random_soup(600, 42);
    const auto rays = probe_rays(scene, 2000, 3);
    for (const std::string& split : kSplits)
        for (const std::string axis : {"longest", "round_robin"})
            for (const std::string traversal : {"ordered", "report"})
                for (const std::string max_prims : {"1", "4"}) {
                    const std::map<std::string, std::string> p = {
                        {"split", split}, {"axis", axis}, {"traversal", traversal}, {"max_prims", max_prims}};
                    auto bvh = built(scene, p);
                    expect_agrees_with_embree(scene, *bvh, rays, describe(p));
                }
}

TEST(Bvh, AgreesWithEmbreeOnLargerLeavesAndOtherBinCounts) {
    const Scene scene = random_soup(2000, 8);
    const auto rays = probe_rays(scene, 2000, 4);
    for (const std::map<std::string, std::string>& p : std::vector<std::map<std::string, std::string>>{
             {{"max_prims", "16"}},
             {{"split", "sah"}, {"max_prims", "8"}, {"bins", "2"}},
             {{"split", "sah"}, {"max_prims", "8"}, {"bins", "64"}, {"traversal_cost", "4"}},
             {{"split", "sah"}, {"traversal_cost", "0"}, {"isect_cost", "10"}},
             {{"split", "sah"}, {"all_axes_min", "1"}},
             {{"split", "sah"}, {"all_axes_min", "1"}, {"max_prims", "1"}, {"bins", "2"}},
             // more than 64 bins: the binning's used-bin words then mark every bin used
             {{"split", "sah"}, {"all_axes_min", "1"}, {"bins", "100"}},
             {{"split", "sah"}, {"all_axes_min", "0"}, {"bins", "100"}},
             {{"split", "midpoint"}, {"max_prims", "3"}, {"traversal", "report"}}}) {
        auto bvh = built(scene, p);
        expect_agrees_with_embree(scene, *bvh, rays, describe(p));
    }
}

// A closed surface of shared edges: a ray hitting an edge must hit one of its triangles
// (watertightness is preserved by the hierarchy: no box may drop a triangle).
TEST(Bvh, AgreesWithEmbreeOnClosedGrid) {
    const Scene scene = closed_grid();
    const auto rays = probe_rays(scene, 3000, 7);
    for (const std::string& split : kSplits)
        for (const std::string traversal : {"ordered", "report"}) {
            const std::map<std::string, std::string> p = {{"split", split}, {"traversal", traversal}};
            expect_agrees_with_embree(scene, *built(scene, p), rays, describe(p) + " grid");
        }
}

// The packet leaf test (leaf_test=packet, split=sah's by default) answers every ray
// exactly as the scalar one on the same tree — the same primitive, t, u and v bit for bit —
// visits the same nodes and tests the same boxes; closest-hit queries test the same
// triangles, any-hit ones at least as many (a hit ends the search after its whole packet).
// Rays from outside and inside the bunny, a closed grid (shared edges) and a random soup,
// the shadow rays from the closest hits; SAH trees with leaves of up to 8 (2 packets) and 3
// (a partial packet), the median tree forced to packets of one triangle; both traversals.
TEST(Bvh, PacketLeavesAnswerExactlyAsScalarLeaves) {
    const std::vector<std::pair<std::string, Scene>> scenes = {
        {"bunny", stanford_bunny()}, {"grid", closed_grid()}, {"soup", random_soup(3000, 5)}};
    const std::vector<std::map<std::string, std::string>> trees = {
        {{"split", "sah"}}, {{"split", "sah"}, {"max_prims", "3"}, {"traversal_cost", "8"}}, {{"split", "median"}}};
    for (const auto& [name, scene] : scenes) {
        const std::vector<Ray> rays = probe_rays(scene, 4000, 11);
        for (const auto& tree : trees)
            for (const std::string traversal : {"ordered", "report"}) {
                auto params = tree;
                params["traversal"] = traversal;
                params["leaf_test"] = "scalar";
                const auto scalar = built(scene, params);
                params["leaf_test"] = "packet";
                const auto packet = built(scene, params);
                const std::string what = name + " " + describe(params);
                std::vector<Hit> hs(rays.size()), hp(rays.size());
                std::vector<RayStats> ss(rays.size()), sp(rays.size());
                scalar->closest_hits(rays, hs, ss);
                packet->closest_hits(rays, hp, sp);
                size_t hits = 0;
                for (size_t i = 0; i < rays.size(); ++i) {
                    ASSERT_EQ(hs[i].prim, hp[i].prim) << what << " ray " << i;
                    EXPECT_EQ(ss[i].node_visits, sp[i].node_visits) << what << " ray " << i;
                    EXPECT_EQ(ss[i].box_tests, sp[i].box_tests) << what << " ray " << i;
                    EXPECT_EQ(ss[i].prim_tests, sp[i].prim_tests) << what << " ray " << i;
                    hits += hs[i].found();
                    if (!hs[i].found()) continue;
                    EXPECT_EQ(std::memcmp(&hs[i].t, &hp[i].t, sizeof(float)), 0) << what << " ray " << i;
                    EXPECT_EQ(std::memcmp(&hs[i].u, &hp[i].u, sizeof(float)), 0) << what << " ray " << i;
                    EXPECT_EQ(std::memcmp(&hs[i].v, &hp[i].v, sizeof(float)), 0) << what << " ray " << i;
                }
                EXPECT_GT(hits, rays.size() / 4) << what;
                const std::vector<Ray> shadow = shadow_rays(scene, rays, hs);
                std::vector<uint8_t> os(shadow.size()), op(shadow.size());
                std::vector<RayStats> as(shadow.size()), ap(shadow.size());
                scalar->any_hits(shadow, os, as);
                packet->any_hits(shadow, op, ap);
                size_t occluded = 0;
                for (size_t i = 0; i < shadow.size(); ++i) {
                    ASSERT_EQ(os[i], op[i]) << what << " shadow ray " << i;
                    occluded += os[i];
                    EXPECT_EQ(as[i].node_visits, ap[i].node_visits) << what << " shadow ray " << i;
                    EXPECT_EQ(as[i].box_tests, ap[i].box_tests) << what << " shadow ray " << i;
                    EXPECT_LE(as[i].prim_tests, ap[i].prim_tests) << what << " shadow ray " << i;
                }
                // Some occluded, some not, or the any-hit comparison would say little.
                if (name != "grid") {
                    EXPECT_GT(occluded, 0u) << what;
                    EXPECT_LT(occluded, shadow.size()) << what;
                }
            }
    }
}

// leaf_test=auto: packets where a leaf may hold more than one triangle, whatever the split;
// the given choice otherwise.
TEST(Bvh, AutomaticLeafTestFollowsTheLeafLimit) {
    auto packets = [](const std::map<std::string, std::string>& p) {
        return Bvh::Config::from(resolve_params("bvh", Bvh::info().params, p)).packet_leaves();
    };
    EXPECT_TRUE(packets({{"split", "sah"}}));
    EXPECT_FALSE(packets({{"split", "sah"}, {"max_prims", "1"}}));
    EXPECT_FALSE(packets({}));
    EXPECT_TRUE(packets({{"max_prims", "2"}}));
    EXPECT_TRUE(packets({{"max_prims", "1"}, {"leaf_test", "packet"}}));
    EXPECT_FALSE(packets({{"split", "sah"}, {"leaf_test", "scalar"}}));
}

// ---- exact trees on hand-made scenes ----------------------------------------------------

TEST(Bvh, EightSeparatedTrianglesGiveTheBalancedTree) {
    const Scene scene = triangles_along_x({0, 1, 2, 3, 4, 5, 6, 7});
    for (const std::string& split : kSplits) {
        // The SAH with a node visit as dear as a triangle test splits down to single
        // triangles here too; at its default traversal_cost (4), see below.
        std::map<std::string, std::string> p = {{"split", split}};
        if (split == "sah") p["traversal_cost"] = "1";
        auto bvh = built(scene, p);
        expect_shape(*bvh, {15, 8, 3}, split);
        EXPECT_EQ(extra(*bvh, "degenerate_splits"), 0) << split;
        EXPECT_EQ(extra(*bvh, "forced_leaves"), 0) << split;
        EXPECT_DOUBLE_EQ(bvh->build_stats().avg_leaf_size.value(), 1.0) << split;
        // Every inner node splits along x, the only axis along which the centroids spread.
        for (const BvhNode& n : bvh->tree().nodes)
            if (!n.is_leaf()) {
                EXPECT_EQ(n.axis(), 0) << split;
            }
        // The leaves come out in x order: slot k holds triangle k.
        for (uint32_t k = 0; k < 8; ++k) EXPECT_EQ(bvh->tree().prim_ids[k], k) << split;
    }
    // SAH at traversal_cost 4 (the default): the triangles are flat (area 2 dx dy), k of them
    // from x = 0 have box area k - 0.5, all eight 7.5. Root: a leaf costs 8 x 7.5 = 60, the
    // best split 4 | 4 costs 4 x 7.5 + 3.5 x 4 + 3.5 x 4 = 58: split. Each half: a leaf 4 x 3.5
    // = 14, its best split 4 x 3.5 + 1.5 x 2 + 1.5 x 2 = 20: leaf. Two leaves of four.
    expect_shape(*built(scene, {{"split", "sah"}}), {3, 2, 1}, "sah default");
    expect_shape(*built(scene, {{"max_prims", "2"}}), {7, 4, 2}, "max_prims=2");
    expect_shape(*built(scene, {{"max_prims", "3"}}), {7, 4, 2}, "max_prims=3");
    expect_shape(*built(scene, {{"max_prims", "8"}}), {1, 1, 0}, "max_prims=8");
}

TEST(Bvh, EightSeparatedTrianglesMetrics) {
    // Triangles of leg 0.5 at x = 0..7, flat in z: box areas are 2 * dx * dy.
    const Scene scene = triangles_along_x({0, 1, 2, 3, 4, 5, 6, 7});
    auto bvh = built(scene, {});
    const BuildStats s = bvh->build_stats();
    // Inner: root dx 7.5; two of dx 3.5; four of dx 1.5 (dy 0.5). Leaves: 8 of 0.5 x 0.5.
    const double inner = 2 * 0.5 * (7.5 + 2 * 3.5 + 4 * 1.5), leaves = 8 * 2 * 0.5 * 0.5, root = 2 * 0.5 * 7.5;
    EXPECT_NEAR(s.sah_cost.value(), (inner + leaves) / root, 1e-12);
    EXPECT_EQ(s.memory_bytes.value(), 15u * 32 + 8u * 4 + 8u * 36);
}

TEST(Bvh, DepthLimitMakesForcedLeaves) {
    const Scene scene = triangles_along_x({0, 1, 2, 3, 4, 5, 6, 7});
    auto one = built(scene, {{"max_depth", "1"}});
    expect_shape(*one, {3, 2, 1}, "max_depth=1");
    EXPECT_EQ(extra(*one, "forced_leaves"), 2);
    EXPECT_DOUBLE_EQ(one->build_stats().avg_leaf_size.value(), 4.0);
    auto zero = built(scene, {{"max_depth", "0"}});
    expect_shape(*zero, {1, 1, 0}, "max_depth=0");
    EXPECT_EQ(extra(*zero, "forced_leaves"), 1);
    // A limit the tree never reaches changes nothing.
    auto deep = built(scene, {{"max_depth", "200"}});
    expect_shape(*deep, {15, 8, 3}, "max_depth=200");
    EXPECT_EQ(extra(*deep, "forced_leaves"), 0);
}

TEST(Bvh, RoundRobinFallsBackOnAxesWithoutSpread) {
    // Centroids spread along x only: round robin asks y at depth 1 (2 nodes) and z at
    // depth 2 (4 nodes); those 6 ranges split by count along x instead.
    const Scene scene = triangles_along_x({0, 1, 2, 3, 4, 5, 6, 7});
    for (const std::string& split : kSplits) {
        auto bvh = built(scene, {{"split", split}, {"axis", "round_robin"}, {"max_prims", "1"}});
        expect_shape(*bvh, {15, 8, 3}, split);
        EXPECT_EQ(extra(*bvh, "degenerate_splits"), 6) << split;
    }
}

TEST(Bvh, SplitCriteriaDifferAsTheReportDescribes) {
    // Centroids at 0.25, 1.25, 2.25, 100.25 along x.
    const Scene outlier = triangles_along_x({0, 1, 2, 100});
    // Object median: 2 | 2.
    expect_shape(*built(outlier, {{"split", "median"}}), {7, 4, 2}, "median");
    // Centroid method: plane 50.25 -> {0,1,2} | {100}; then plane 1.25 -> {0} | {1,2}.
    expect_shape(*built(outlier, {{"split", "midpoint"}}), {7, 4, 3}, "midpoint");
    // Mean 25.75 -> {0,1,2} | {100}; then mean 1.25 -> {0} | {1,2}.
    expect_shape(*built(outlier, {{"split", "mean"}}), {7, 4, 3}, "mean");
    // SAH (traversal_cost 1) cuts off the outlier's empty space first. (At the default 4 the
    // four are one leaf: 4 x 100.5 against 4 x 100.5 + 2.5 x 3 + 0.5 for the best split.)
    expect_shape(*built(outlier, {{"split", "sah"}, {"traversal_cost", "1"}}), {7, 4, 3}, "sah");
    expect_shape(*built(outlier, {{"split", "sah"}}), {1, 1, 0}, "sah default");

    // Spatial median, the report's example (Figure 5c): sizes {1, 1, 1, 4} -> areas
    // {1, 1, 1, 16}: the big one alone on one side.
    Scene sizes;
    for (int i = 0; i < 4; ++i) {
        const float x = 10.0f * float(i), leg = i == 3 ? 4.0f : 1.0f;
        add_triangle(sizes, {x, 0, 0}, {x + leg, 0, 0}, {x, leg, 0});
    }
    sizes.finalize();
    auto spatial = built(sizes, {{"split", "spatial_median"}});
    expect_shape(*spatial, {7, 4, 3}, "spatial_median");
    const BvhNode& root = spatial->tree().nodes[0];
    const BvhNode& second = spatial->tree().nodes[root.second_child()];
    ASSERT_TRUE(second.is_leaf());
    EXPECT_EQ(spatial->tree().prim_ids[second.first_prim()], 3u);
    expect_shape(*built(sizes, {{"split", "median"}}), {7, 4, 2}, "median sizes");
}

TEST(Bvh, SahStopsEarlyOnlyWhenALeafIsCheaper) {
    // Four separated triangles: with a node visit as dear as a triangle test (traversal_cost
    // 1) splitting pays, so SAH makes single-triangle leaves even though max_prims allows a
    // leaf of 4 (median makes that one leaf).
    const Scene separated = triangles_along_x({0, 1, 2, 3});
    expect_shape(*built(separated, {{"split", "sah"}, {"max_prims", "4"}, {"traversal_cost", "1"}}), {7, 4, 2},
                 "sah separated");
    // At the default traversal_cost 4 a leaf is cheaper: 4 x 3.5 = 14 against 4 x 3.5 + 1.5 x 2
    // + 1.5 x 2 = 20 for the best split.
    expect_shape(*built(separated, {{"split", "sah"}, {"max_prims", "4"}}), {1, 1, 0}, "sah separated default");
    expect_shape(*built(separated, {{"split", "median"}, {"max_prims", "4"}}), {1, 1, 0}, "median separated");
    // Four nearly coincident triangles: any split costs more than one leaf of 4.
    const Scene stacked = triangles_along_x({0, 0.01f, 0.02f, 0.03f}, 1.0f);
    expect_shape(*built(stacked, {{"split", "sah"}, {"max_prims", "4"}}), {1, 1, 0}, "sah stacked");
    // ... but with max_prims 2 it must split.
    expect_shape(*built(stacked, {{"split", "sah"}, {"max_prims", "2"}}), {3, 2, 1}, "sah stacked max_prims=2");
}

// Two rows of eight triangles along x, ten apart in y: the centroid box is longest in x
// (17.5 against 10), and every x plane cuts both rows (children 11 high); a y plane separates
// them: A_left N_left + A_right N_right = 37 x 8 + 37 x 8 = 592, against 2 x 187 x 8 = 2992
// for the even x plane. all_axes_min says from which range size the y plane is seen.
TEST(Bvh, AllAxesFindThePlaneTheLongestAxisMisses) {
    Scene rows;
    rows.name = "test-two-rows";
    for (int row = 0; row < 2; ++row)
        for (int i = 0; i < 8; ++i) {
            const float x = 2.5f * float(i), y = 10.0f * float(row);
            add_triangle(rows, {x, y, 0}, {x + 1, y, 0}, {x, y + 1, 0});
        }
    rows.finalize();
    auto children_height = [&](const std::map<std::string, std::string>& extra) {
        std::map<std::string, std::string> p = {{"split", "sah"}};
        p.insert(extra.begin(), extra.end());
        auto bvh = built(rows, p);
        const FlatBvh& t = bvh->tree();
        EXPECT_FALSE(t.nodes[0].is_leaf()) << describe(p);
        if (t.nodes[0].is_leaf()) return 0.0f;
        return std::max(t.nodes[1].bounds.diagonal().y, t.nodes[t.nodes[0].second_child()].bounds.diagonal().y);
    };
    EXPECT_EQ(children_height({{"all_axes_min", "1"}}), 1.0f);    // every range
    EXPECT_EQ(children_height({{"all_axes_min", "16"}}), 1.0f);   // the root's 16 triangles are enough
    EXPECT_EQ(children_height({{"all_axes_min", "17"}}), 11.0f);  // too few: the longest axis, x
    EXPECT_EQ(children_height({{"all_axes_min", "0"}}), 11.0f);   // none
    EXPECT_EQ(children_height({}), 11.0f);                        // the default, 1024
    // round_robin starts at x too; with all axes its rule no longer picks the root's plane.
    EXPECT_EQ(children_height({{"axis", "round_robin"}, {"all_axes_min", "0"}}), 11.0f);
    EXPECT_EQ(children_height({{"axis", "round_robin"}, {"all_axes_min", "1"}}), 1.0f);
    EXPECT_LT(built(rows, {{"split", "sah"}, {"all_axes_min", "1"}})->build_stats().sah_cost.value(),
              built(rows, {{"split", "sah"}})->build_stats().sah_cost.value());
}

TEST(Bvh, CountsOfOrderedTraversalOnHandScene) {
    // A ray straight down onto triangle 5 of the eight: the root box, then two child boxes
    // per level on the way down (3 levels), with both children of a level tested; only the
    // boxes on the path are hit (the others lie beside the ray), so 3 inner nodes + 1 leaf
    // are entered and one triangle is tested.
    const Scene scene = triangles_along_x({0, 1, 2, 3, 4, 5, 6, 7});
    for (const std::string traversal : {"ordered", "report"}) {
        auto bvh = built(scene, {{"traversal", traversal}});
        const Ray ray{{5.1f, 0.1f, 1}, 0.0f, {0, 0, -1}, kInfinity};
        std::vector<Hit> hits(1);
        std::vector<RayStats> stats(1);
        bvh->closest_hits({&ray, 1}, hits, stats);
        EXPECT_EQ(hits[0].prim, 5u) << traversal;
        EXPECT_EQ(stats[0].prim_tests, 1u) << traversal;
        if (traversal == "ordered") {
            EXPECT_EQ(stats[0].node_visits, 4u);
            EXPECT_EQ(stats[0].box_tests, 1u + 3 * 2);
        } else {
            // Algorithm 1 enters both children of each node on the path and tests their
            // boxes there: root + 2 per level.
            EXPECT_EQ(stats[0].node_visits, 7u);
            EXPECT_EQ(stats[0].box_tests, 7u);
        }
    }
}

// ---- degenerate input terminates ------------------------------------------------------

TEST(Bvh, IdenticalTrianglesBuildAndTerminate) {
    Scene scene;
    for (int i = 0; i < 100; ++i) add_triangle(scene, {0, 0, 0}, {1, 0, 0}, {0, 1, 0.5f});
    scene.finalize();
    for (const std::string& split : kSplits) {
        auto bvh = built(scene, {{"split", split}, {"max_prims", "1"}});
        // Every range is split in two by count: 199 nodes, depth ceil(log2 100) = 7.
        expect_shape(*bvh, {199, 100, 7}, split);
        EXPECT_EQ(extra(*bvh, "degenerate_splits"), 99) << split;
        expect_agrees_with_embree(scene, *bvh, probe_rays(scene, 500), "identical " + split);
    }
    // SAH with max_prims 100 keeps them in one leaf: nothing separates them.
    auto leaf = built(scene, {{"split", "sah"}, {"max_prims", "100"}});
    expect_shape(*leaf, {1, 1, 0}, "sah one leaf");
    EXPECT_EQ(extra(*leaf, "degenerate_splits"), 0);
}

TEST(Bvh, CommonCentroidBuildsAndAgrees) {
    const Scene scene = common_centroid_scene(300);
    for (const std::string& split : kSplits)
        for (const std::string traversal : {"ordered", "report"}) {
            auto bvh = built(scene, {{"split", split}, {"traversal", traversal}, {"max_prims", "1"}});
            EXPECT_EQ(bvh->build_stats().nodes.value(), 599u) << split;
            EXPECT_EQ(extra(*bvh, "degenerate_splits"), 299) << split;
            expect_agrees_with_embree(scene, *bvh, probe_rays(scene, 1000, 2), "common centroid " + split);
        }
}

TEST(Bvh, FlatSceneAgrees) {
    Scene scene = random_soup(800, 17);
    for (Vec3& v : scene.vertices) v.z = 0.5f;  // zero extent along z
    scene.finalize();
    for (const std::string& split : kSplits)
        for (const std::string axis : {"longest", "round_robin"}) {
            const std::map<std::string, std::string> p = {{"split", split}, {"axis", axis}};
            expect_agrees_with_embree(scene, *built(scene, p), probe_rays(scene, 1500, 5), describe(p) + " flat");
        }
}

TEST(Bvh, SingleTriangle) {
    const Scene scene = triangles_along_x({0});
    for (const std::string& split : kSplits) {
        auto bvh = built(scene, {{"split", split}});
        expect_shape(*bvh, {1, 1, 0}, split);
        std::vector<Ray> rays = {{{0.1f, 0.1f, 1}, 0, {0, 0, -1}, kInfinity},
                                 {{0.4f, 0.4f, 1}, 0, {0, 0, -1}, kInfinity}};
        std::vector<Hit> hits(2);
        bvh->closest_hits(rays, hits);
        EXPECT_EQ(hits[0].prim, 0u);
        EXPECT_FLOAT_EQ(hits[0].t, 1.0f);
        EXPECT_FALSE(hits[1].found());  // beyond the hypotenuse
    }
}

TEST(Bvh, EmptySceneBuildsAndMisses) {
    Scene scene;
    scene.finalize();
    for (const std::string traversal : {"ordered", "report"}) {
        auto bvh = built(scene, {{"traversal", traversal}});
        const BuildStats s = bvh->build_stats();
        EXPECT_EQ(s.nodes.value(), 0u);
        EXPECT_EQ(s.leaves.value(), 0u);
        EXPECT_FALSE(s.sah_cost.has_value());
        const Ray ray{{0, 0, 1}, 0, {0, 0, -1}, kInfinity};
        std::vector<Hit> hits(1);
        std::vector<uint8_t> occluded(1, 1);
        bvh->closest_hits({&ray, 1}, hits);
        bvh->any_hits({&ray, 1}, occluded);
        EXPECT_FALSE(hits[0].found());
        EXPECT_EQ(occluded[0], 0);
    }
}

TEST(Bvh, DepthLimitsOnSoup) {
    const Scene scene = random_soup(1000, 99);
    const auto rays = probe_rays(scene, 1500, 9);
    for (const std::string& split : kSplits) {
        auto shallow = built(scene, {{"split", split}, {"max_depth", "1"}, {"max_prims", "1"}});
        EXPECT_LE(shallow->build_stats().max_depth.value(), 1u) << split;
        EXPECT_EQ(extra(*shallow, "forced_leaves"), 2) << split;
        expect_agrees_with_embree(scene, *shallow, rays, "max_depth=1 " + split);
        auto deep = built(scene, {{"split", split}, {"max_depth", "200"}, {"max_prims", "1"}});
        EXPECT_EQ(extra(*deep, "forced_leaves"), 0) << split;
        EXPECT_EQ(deep->build_stats().leaves.value(), 1000u) << split;
        expect_agrees_with_embree(scene, *deep, rays, "max_depth=200 " + split);
    }
}

TEST(Bvh, MidpointOnExponentialSpacingGoesDeepAndStaysCorrect) {
    // Triangle i spans [x_i, 1.25 x_i] in x (and [0, 1] in y) with x_i = 2.5^(i-45)
    // (within Embree's coordinate range): the centroid method's plane, about half the
    // largest centroid, always lies beyond all but the largest triangle, so it peels one
    // triangle per level and the tree is as deep as the scene is large (deeper than the
    // traversal's inline stack).
    Scene scene;
    const int n = 90;
    auto x_of = [](int i) { return float(std::pow(2.5, i - 45)); };
    for (int i = 0; i < n; ++i) add_triangle(scene, {x_of(i), 0, 0}, {1.25f * x_of(i), 0, 0}, {x_of(i), 1, 0});
    scene.finalize();
    // Probe rays mostly see the largest triangles; add one ray straight down onto each.
    std::vector<Ray> rays = probe_rays(scene, 500, 4);
    for (int i = 0; i < n; ++i) rays.push_back({{1.05f * x_of(i), 0.05f, 1}, 0.0f, {0, 0, -1}, kInfinity});
    auto bvh = built(scene, {{"split", "midpoint"}, {"max_depth", "200"}});
    EXPECT_EQ(bvh->build_stats().max_depth.value(), uint64_t(n - 1));
    expect_agrees_with_embree(scene, *bvh, rays, "midpoint exponential");
    std::vector<Hit> hits(rays.size());
    bvh->closest_hits(rays, hits);
    for (int i = 0; i < n; ++i) EXPECT_EQ(hits[500 + i].prim, uint32_t(i));
    auto capped = built(scene, {{"split", "midpoint"}, {"max_depth", "50"}});
    EXPECT_EQ(capped->build_stats().max_depth.value(), 50u);
    EXPECT_EQ(extra(*capped, "forced_leaves"), 1);
    expect_agrees_with_embree(scene, *capped, rays, "midpoint exponential capped");
}

TEST(Bvh, ParametersAreValidated) {
    EXPECT_THROW(make_accelerator("bvh", {{"split", "hlbvh"}}), ParamError);
    EXPECT_THROW(make_accelerator("bvh", {{"max_prims", "0"}}), ParamError);
    EXPECT_THROW(make_accelerator("bvh", {{"bins", "1"}}), ParamError);
    EXPECT_THROW(make_accelerator("bvh", {{"traversal", "stackless"}}), ParamError);
    EXPECT_THROW(make_accelerator("bvh", {{"all_axes_min", "-1"}}), ParamError);
    EXPECT_NO_THROW(make_accelerator("bvh", {{"split", "sah"}, {"bins", "32"}, {"axis", "round_robin"}}));
}

// ---- a real model ---------------------------------------------------------------------

TEST(Bvh, StanfordBunnyAgreesWithEmbree) {
    const Scene scene = test::stanford_bunny();
    ASSERT_EQ(scene.triangle_count(), 69451u);
    const auto rays = probe_rays(scene, 20000, 11);
    for (const std::map<std::string, std::string>& p : std::vector<std::map<std::string, std::string>>{
             {}, {{"split", "sah"}}, {{"split", "sah"}, {"max_prims", "8"}, {"traversal", "report"}}}) {
        auto bvh = built(scene, p);
        const BuildStats s = bvh->build_stats();
        if (p.count("max_prims") == 0 && !p.count("split")) {           // the median's max_prims default: 1
            EXPECT_EQ(s.nodes.value(), 2u * 69451 - 1) << describe(p);  // one triangle per leaf
            EXPECT_EQ(s.leaves.value(), 69451u) << describe(p);
        }
        if (p.empty()) {
            EXPECT_EQ(s.max_depth.value(), 17u);  // median: ceil(log2 69451)
        }
        std::printf("[bunny] %s: nodes %llu, depth %llu, sah %.2f, degenerate %g, forced %g\n", describe(p).c_str(),
                    (unsigned long long)s.nodes.value(), (unsigned long long)s.max_depth.value(), s.sah_cost.value(),
                    s.extra.at("degenerate_splits"), s.extra.at("forced_leaves"));
        expect_agrees_with_embree(scene, *bvh, rays, describe(p) + " bunny");
    }
}

// ---- the median build is the same tree as the in-place one's --------------------------
//
// The median build (split=median, the report's default) was rewritten for speed
// with the promise of the same tree: the same nodes, leaves and primitive order,
// byte for byte. The reference below is the earlier in-place algorithm (42f25d3) frozen here
// as the specification, written recursively: the equal-count split (bins, a three-way
// scatter, std::nth_element inside the median's bin) on 28-byte references moved in place,
// then a separate fit of each child. std::nth_element's tie-breaking among equal centroids
// depends on the exact order of its input, so any change to the order in which the new
// build moves references shows up here as a different tree.

namespace {

struct ReferenceRef {
    Bounds3 bounds;
    uint32_t id;
    float centroid(int axis) const { return 0.5f * (bounds.lower[axis] + bounds.upper[axis]); }
};

void reference_equal_counts(std::span<ReferenceRef> refs, std::vector<ReferenceRef>& scratch, int axis, float lo,
                            float hi) {
    const size_t n = refs.size(), mid = n / 2;
    auto by_centroid = [axis](const ReferenceRef& x, const ReferenceRef& y) {
        return x.centroid(axis) < y.centroid(axis);
    };
    if (n <= 3) {
        auto order = [&](size_t i, size_t j) {
            if (by_centroid(refs[j], refs[i])) std::swap(refs[i], refs[j]);
        };
        if (n >= 2) order(0, 1);
        if (n == 3) {
            order(1, 2);
            order(0, 1);
        }
        return;
    }
    if (n < 16 || !(hi > lo)) {
        std::nth_element(refs.begin(), refs.begin() + ptrdiff_t(mid), refs.end(), by_centroid);
        return;
    }
    const uint32_t bins = uint32_t(std::min<size_t>(256, n / 4));
    const float scale = float(bins) * (1.0f - 1e-6f) / (hi - lo);
    auto bin_of = [&](const ReferenceRef& r) {
        return uint32_t(std::min(float(bins - 1), std::max(0.0f, (r.centroid(axis) - lo) * scale)));
    };
    std::vector<uint32_t> counts(bins, 0);
    for (const ReferenceRef& r : refs) ++counts[bin_of(r)];
    uint32_t median_bin = 0, below = 0;
    while (below + counts[median_bin] <= mid) below += counts[median_bin++];
    size_t next[3] = {0, below, below + counts[median_bin]};
    scratch.resize(n);
    for (const ReferenceRef& r : refs) {
        const uint32_t b = bin_of(r);
        scratch[next[int(b >= median_bin) + int(b > median_bin)]++] = r;
    }
    std::copy(scratch.begin(), scratch.begin() + ptrdiff_t(n), refs.begin());
    std::nth_element(refs.begin() + ptrdiff_t(below), refs.begin() + ptrdiff_t(mid),
                     refs.begin() + ptrdiff_t(below + counts[median_bin]), by_centroid);
}

// Builds the subtree of refs[begin, end) in depth-first order; returns its root's index.
uint32_t reference_median_node(std::vector<ReferenceRef>& refs, std::vector<ReferenceRef>& scratch, uint32_t begin,
                               uint32_t end, uint32_t depth, const BvhTopDownSettings& s, FlatBvh& out) {
    Bounds3 box, centroids;
    for (uint32_t i = begin; i < end; ++i) {
        box.extend(refs[i].bounds);
        centroids.extend(refs[i].bounds.center());
    }
    const uint32_t index = uint32_t(out.nodes.size());
    const uint32_t count = end - begin;
    out.nodes.push_back(BvhNode::leaf(box, begin, count));
    out.depth = std::max(out.depth, depth);
    if (count <= 1 || depth >= s.max_depth || count <= s.max_prims) return index;
    const Vec3 extent = centroids.diagonal();
    int axis = s.axis == BvhAxisRule::longest ? max_axis(extent) : int(depth % 3);
    if (!(extent[axis] > 0.0f)) axis = max_axis(extent);  // the degenerate fallback: the longest axis
    reference_equal_counts(std::span(refs).subspan(begin, count), scratch, axis, centroids.lower[axis],
                           centroids.upper[axis]);
    const uint32_t mid = begin + count / 2;
    out.nodes[index] = BvhNode::inner(box, 0, axis);
    reference_median_node(refs, scratch, begin, mid, depth + 1, s, out);
    const uint32_t second = reference_median_node(refs, scratch, mid, end, depth + 1, s, out);
    out.nodes[index].index = second;
    return index;
}

FlatBvh reference_median_bvh(const Scene& scene, const BvhTopDownSettings& s) {
    std::vector<ReferenceRef> refs(scene.triangle_count()), scratch;
    for (uint32_t i = 0; i < refs.size(); ++i) refs[i] = {scene.prim_bounds[i], i};
    FlatBvh out;
    if (!refs.empty()) reference_median_node(refs, scratch, 0, uint32_t(refs.size()), 0, s, out);
    for (const ReferenceRef& r : refs) out.prim_ids.push_back(r.id);
    return out;
}

void expect_same_tree_as_reference(const Scene& scene, const std::map<std::string, std::string>& params,
                                   const BvhTopDownSettings& s) {
    const std::string what = scene.name + " " + describe(params);
    auto bvh = built(scene, params);
    const FlatBvh want = reference_median_bvh(scene, s);
    const FlatBvh& got = bvh->tree();
    ASSERT_EQ(got.nodes.size(), want.nodes.size()) << what;
    EXPECT_EQ(std::memcmp(got.nodes.data(), want.nodes.data(), want.nodes.size() * sizeof(BvhNode)), 0) << what;
    EXPECT_EQ(got.prim_ids, want.prim_ids) << what;
    EXPECT_EQ(got.depth, want.depth) << what;
}

}  // namespace

TEST(Bvh, MedianBuildIsInPlaceTreeByteForByte) {
    const std::vector<Scene> scenes = {test::stanford_bunny(), closed_grid(), random_soup(3000, 17),
                                       common_centroid_scene(200), triangles_along_x({0, 0, 0, 1, 1, 2, 5, 5, 5, 5})};
    for (const Scene& scene : scenes) {
        expect_same_tree_as_reference(scene, {{"split", "median"}}, {});
        expect_same_tree_as_reference(scene, {{"split", "median"}, {"axis", "round_robin"}},
                                      {1, 50, BvhAxisRule::round_robin});
        expect_same_tree_as_reference(scene, {{"split", "median"}, {"max_prims", "3"}, {"max_depth", "9"}},
                                      {3, 9, BvhAxisRule::longest});
    }
}
