// Every parallel build gives the tree of its one-thread build: the node arrays (and the leaf
// arrays beside them) byte for byte at 1, 2 and 7 threads, on the bunny and the procedural
// scenes, for bvh (every split), wbvh (both widths and collapses), lbvh and kdtree (both
// builds). The scenes are
// large enough (more than 64k triangles) that the parallel paths run: the root's split
// binned and partitioned in blocks, subtrees handed out as tasks, the pieces assembled.
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "accelbench/accel/bvh/bvh.h"
#include "accelbench/accel/bvh/lbvh.h"
#include "accelbench/accel/bvh/wbvh.h"
#include "accelbench/accel/kdtree/kdtree.h"
#include "accelbench/accel/registry.h"
#include "accelbench/scene/procedural.h"
#include "agreement.h"
#include "test_scenes.h"

using namespace accelbench;

namespace {

using Params = std::map<std::string, std::string>;

template <class T>
std::unique_ptr<T> built(const char* name, const Scene& scene, Params params, const char* threads) {
    params["threads"] = threads;
    auto accel = make_accelerator(name, params);
    std::unique_ptr<T> t(static_cast<T*>(accel.release()));
    t->build(scene);
    return t;
}

std::string describe(const char* name, const Params& params, const char* threads) {
    std::string s = name;
    for (const auto& [k, v] : params) s += " " + k + "=" + v;
    return s + " threads=" + threads;
}

// Two arrays of trivially copyable elements, byte for byte (the first differing element named).
template <class A, class B>
void expect_same_bytes(const A& a, const B& b, const std::string& what) {
    ASSERT_EQ(a.size(), b.size()) << what;
    for (size_t i = 0; i < a.size(); ++i)
        ASSERT_EQ(std::memcmp(&a[i], &b[i], sizeof(a[i])), 0) << what << ": element " << i;
}

void expect_same_tree(const FlatBvh& a, const FlatBvh& b, const std::string& what) {
    expect_same_bytes(a.nodes, b.nodes, what + " nodes");
    EXPECT_EQ(a.prim_ids, b.prim_ids) << what;
    expect_same_bytes(a.triangles, b.triangles, what + " triangles");
    EXPECT_EQ(a.depth, b.depth) << what;
}

template <int W>
void expect_same_tree(const WbvhTree<W>& a, const WbvhTree<W>& b, const std::string& what) {
    expect_same_bytes(a.nodes, b.nodes, what + " nodes");
    expect_same_bytes(a.packets, b.packets, what + " packets");
    EXPECT_EQ(a.depth, b.depth) << what;
    EXPECT_EQ(a.leaves, b.leaves) << what;
}

// The bunny and the three procedural kinds at 70,000 triangles.
std::vector<Scene> scenes() {
    std::vector<Scene> out;
    out.push_back(test::stanford_bunny());
    for (const char* kind : {"forest", "city", "soup"})
        out.push_back(make_procedural(kind, {{"triangles", "70000"}, {"seed", "3"}}));
    return out;
}

const std::vector<Scene>& shared_scenes() {
    static const std::vector<Scene> s = scenes();
    return s;
}

constexpr const char* kThreads[] = {"2", "7"};

}  // namespace

TEST(BuildThreads, BvhIsTheSameForEveryThreadCount) {
    const std::vector<Params> variants = {
        {{"split", "median"}},
        {{"split", "midpoint"}},
        {{"split", "mean"}},
        {{"split", "spatial_median"}},
        {{"split", "sah"}},                         // packet leaves
        {{"split", "sah"}, {"max_prims", "1"}},     // tasks write in place
        {{"split", "sah"}, {"all_axes_min", "0"}},  // one axis binned in blocks
        {{"split", "median"}, {"max_depth", "9"}},  // forced leaves: in place, then again in pieces
        {{"split", "sah"}, {"max_prims", "1"}, {"max_depth", "12"}},
    };
    for (const Scene& scene : shared_scenes())
        for (const Params& p : variants) {
            const auto one = built<Bvh>("bvh", scene, p, "1");
            for (const char* threads : kThreads) {
                const auto many = built<Bvh>("bvh", scene, p, threads);
                const std::string what = scene.name + " " + describe("bvh", p, threads);
                expect_same_tree(one->tree(), many->tree(), what);
                ASSERT_EQ(one->packet_leaves() != nullptr, many->packet_leaves() != nullptr) << what;
                if (one->packet_leaves()) {
                    expect_same_bytes(one->packet_leaves()->packets, many->packet_leaves()->packets, what + " packets");
                    EXPECT_EQ(one->packet_leaves()->first_packet, many->packet_leaves()->first_packet) << what;
                }
                EXPECT_EQ(one->build_stats().extra, many->build_stats().extra) << what;
            }
        }
}

TEST(BuildThreads, WbvhIsTheSameForEveryThreadCount) {
    for (const Scene& scene : shared_scenes())
        for (const char* width : {"4", "8"})
            for (const char* collapse : {"greedy", "sah"}) {
                const Params p = {{"width", width}, {"collapse", collapse}};
                const auto one = built<Wbvh>("wbvh", scene, p, "1");
                for (const char* threads : kThreads) {
                    const auto many = built<Wbvh>("wbvh", scene, p, threads);
                    const std::string what = scene.name + " " + describe("wbvh", p, threads);
                    if (std::string(width) == "4") expect_same_tree(one->tree4(), many->tree4(), what);
                    else expect_same_tree(one->tree8(), many->tree8(), what);
                }
            }
}

TEST(BuildThreads, LbvhIsTheSameForEveryThreadCount) {
    for (const Scene& scene : shared_scenes())
        for (const Params& p : std::vector<Params>{{}, {{"max_prims", "4"}}, {{"build", "median"}}}) {
            const auto one = built<Lbvh>("lbvh", scene, p, "1");
            for (const char* threads : kThreads)
                expect_same_tree(one->tree(), built<Lbvh>("lbvh", scene, p, threads)->tree(),
                                 scene.name + " " + describe("lbvh", p, threads));
        }
}

TEST(BuildThreads, KdTreeIsTheSameForEveryThreadCount) {
    const std::vector<Params> variants = {{}, {{"build", "pbrt"}}, {{"max_prims", "4"}}, {{"max_depth", "12"}}};
    for (const Scene& scene : shared_scenes())
        for (const Params& p : variants) {
            if (p.count("build") && scene.name != shared_scenes()[0].name) continue;  // pbrt's build is slow: the bunny
            const auto one = built<KdTree>("kdtree", scene, p, "1");
            for (const char* threads : kThreads) {
                const auto many = built<KdTree>("kdtree", scene, p, threads);
                const std::string what = scene.name + " " + describe("kdtree", p, threads);
                expect_same_bytes(one->nodes(), many->nodes(), what + " nodes");
                expect_same_bytes(one->prim_indices(), many->prim_indices(), what + " prim_indices");
                EXPECT_EQ(one->build_stats().extra, many->build_stats().extra) << what;
                EXPECT_EQ(one->deepest_leaf(), many->deepest_leaf()) << what;
            }
        }
}

// The kd-tree's reference budget stops a build on several threads as on one (the count of
// references only grows, so the batches' order does not matter).
TEST(BuildThreads, KdTreeBudgetStopsEveryThreadCount) {
    const Scene& scene = shared_scenes()[0];
    for (const char* threads : {"1", "2", "7"}) {
        KdTree::Config tight;
        tight.max_refs = scene.triangle_count() + 10000;
        tight.threads = std::stoi(threads);
        KdTree kd(tight);
        EXPECT_THROW(kd.build(scene), std::runtime_error) << threads;
        EXPECT_TRUE(kd.nodes().empty()) << threads;
    }
}

// A rebuild on several threads reuses the structure's arrays: it must give the same tree
// again, and answer as Embree does.
TEST(BuildThreads, RebuildsOnSeveralThreadsAgreeWithEmbree) {
    const Scene& scene = shared_scenes()[1];
    const auto rays = test::probe_rays(scene, 2000);
    for (const char* name : {"bvh", "wbvh", "kdtree"}) {
        auto accel = make_accelerator(name, {{"threads", "2"}});
        accel->build(scene);
        accel->build(scene);
        test::expect_agrees_with_embree(scene, *accel, rays, std::string(name) + " threads=2, built twice");
    }
}
