// The open peers as plugins (examples/plugins/peers: tinybvh's BVH, BVH4_CPU, BVH8_CPU and
// bvh v2's DefaultBuilder) answer like Embree on the procedural scenes: no ray that Embree
// sees hit is missed, no primitive differs beyond a tie. Built where ../shared/peers has
// their sources; skipped, saying so, where it has not.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "accelbench/accel/registry.h"
#include "accelbench/scene/procedural.h"
#include "agreement.h"
#include "config/config.h"

namespace accelbench {
namespace {

// The procedural scenes, and the forest shrunk by 2^-12 (about 0.01 across, as the bench
// models' are 0.1-0.3): its triangles as small as the 871k dragon's, where a triangle
// test with an absolute bound on its determinant (tinybvh's BVH layout, unless its plugin
// scales the rays) misses them.
Scene peer_scene(const std::string& kind) {
    if (kind != "small forest") return make_procedural(kind, {{"triangles", "20000"}, {"seed", "3"}});
    Scene scene = make_procedural("forest", {{"triangles", "20000"}, {"seed", "3"}});
    for (Vec3& v : scene.vertices) v = v * std::ldexp(1.0f, -12);
    scene.name = "small forest";
    scene.finalize();
    return scene;
}

void expect_peer_agrees(const char* file,
                        const std::vector<std::pair<const char*, std::map<std::string, std::string>>>& runs) {
    const std::string path = std::string(ACCELBENCH_PEER_PLUGIN_DIR) + "/" + file;
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not built: ../shared/peers lacks its library";
    load_plugin_file(path);
    for (const char* kind : {"forest", "city", "soup", "small forest"}) {
        const Scene scene = peer_scene(kind);
        const std::vector<Ray> rays = test::probe_rays(scene, 3000);
        for (const auto& [name, params] : runs) {
            auto accel = make_accelerator(name, params);
            accel->build(scene);
            std::string what = std::string(name) + " on " + kind;
            for (const auto& [k, v] : params) what += " " + k + "=" + v;
            const test::Agreement a = test::compare_with_embree(scene, *accel, rays);
            std::printf(
                "[peer agreement] %s: %zu rays, %zu hit/miss mismatches, %zu prim mismatches, %zu ties, "
                "%zu shadow mismatches\n",
                what.c_str(), a.rays, a.mismatched_hit, a.mismatched_prim, a.ties, a.mismatched_occlusion);
            EXPECT_EQ(a.mismatched_hit, 0u) << what;
            EXPECT_EQ(a.mismatched_prim, 0u) << what;
            EXPECT_EQ(a.mismatched_occlusion, 0u) << what;
        }
    }
}

// Rays that leave a surface, with [tmin, tmax) past it: three squares across the z axis at
// z = 0, 0.25 and 2, rays along +z. tinybvh's rays have no tmin; its plugin traces from the
// ray's own origin and, where the nearest hit lies before tmin (the square the ray starts
// on, or one crossed before tmin), from org + tmin * dir. Every answer must be the
// reference's: the square past tmin, or nothing when none lies within the interval.
void expect_tmin_kept(const char* file, std::initializer_list<const char*> names) {
    const std::string path = std::string(ACCELBENCH_PEER_PLUGIN_DIR) + "/" + file;
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not built: ../shared/peers lacks its library";
    load_plugin_file(path);
    Scene scene;
    scene.name = "three squares";
    for (float z : {0.0f, 0.25f, 2.0f}) {
        const uint32_t b = uint32_t(scene.vertices.size());
        scene.vertices.insert(scene.vertices.end(), {{-1, -1, z}, {1, -1, z}, {1, 1, z}, {-1, 1, z}});
        scene.triangles.push_back({b, b + 1, b + 2});
        scene.triangles.push_back({b, b + 2, b + 3});
    }
    scene.finalize();
    const Vec3 up{0, 0, 1};
    const std::vector<Ray> rays = {
        {{0.1f, 0.2f, 0.0f}, 0.5f, up, 10.0f},   // starts on z = 0, crosses 0.25 before tmin: z = 2 at t = 2
        {{0.1f, 0.2f, 0.0f}, 0.5f, up, 1.5f},    // the same, the interval ends before z = 2: nothing
        {{0.1f, 0.2f, -1.0f}, 0.5f, up, 10.0f},  // the nearest hit (z = 0, t = 1) is past tmin
        {{0.1f, 0.2f, -1.0f}, 1.1f, up, 10.0f},  // z = 0 lies before tmin: z = 0.25 at t = 1.25
        {{0.1f, 0.2f, 0.3f}, 2.0f, up, 10.0f},   // every square before tmin: nothing
    };
    auto reference = make_accelerator("reference", {});
    reference->build(scene);
    std::vector<Hit> want(rays.size());
    std::vector<uint8_t> want_occluded(rays.size());
    reference->closest_hits(rays, want);
    reference->any_hits(rays, want_occluded);
    ASSERT_EQ(std::count(want_occluded.begin(), want_occluded.end(), 1), 3);  // the scene is what it says
    for (const char* name : names) {
        auto accel = make_accelerator(name, {});
        accel->build(scene);
        std::vector<Hit> got(rays.size());
        std::vector<uint8_t> occluded(rays.size());
        accel->closest_hits(rays, got);
        accel->any_hits(rays, occluded);
        for (size_t i = 0; i < rays.size(); ++i) {
            EXPECT_EQ(got[i].found(), want[i].found()) << name << " ray " << i;
            EXPECT_EQ(got[i].prim / 2, want[i].prim / 2) << name << " ray " << i << ": another square";
            if (want[i].found()) {
                EXPECT_NEAR(got[i].t, want[i].t, 1e-6f) << name << " ray " << i;
            }
            EXPECT_EQ(occluded[i], want_occluded[i]) << name << " ray " << i;
        }
    }
}

TEST(PeerPlugins, TinybvhKeepsTmin) { expect_tmin_kept("tinybvh.so", {"tinybvh_bvh", "tinybvh_bvh4", "tinybvh_bvh8"}); }

TEST(PeerPlugins, BvhV2KeepsTmin) { expect_tmin_kept("bvh2.so", {"bvh2"}); }

TEST(PeerPlugins, TinybvhAgreesWithEmbree) {
    expect_peer_agrees("tinybvh.so",
                       {{"tinybvh_bvh", {}},
                        {"tinybvh_bvh", {{"builder", "hq"}}},
                        {"tinybvh_bvh4", {}},
                        {"tinybvh_bvh8", {}},
                        {"tinybvh_bvh8", {{"builder", "hq"}}}});
}

TEST(PeerPlugins, BvhV2AgreesWithEmbree) {
    expect_peer_agrees("bvh2.so", {{"bvh2", {}}, {"bvh2", {{"quality", "low"}}}, {"bvh2", {{"robust", "true"}}}});
}

}  // namespace
}  // namespace accelbench
