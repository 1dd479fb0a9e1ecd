// The open peers as plugins (examples/plugins/peers: tinybvh's BVH, BVH4_CPU, BVH8_CPU and
// bvh v2's DefaultBuilder) answer like Embree on the procedural scenes: no ray that Embree
// sees hit is missed, no primitive differs beyond a tie. Built where ../shared/peers has
// their sources; skipped, saying so, where it has not.
#include <gtest/gtest.h>

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
