#include "accelbench/accel/baseline/brute_force.h"

#include <gtest/gtest.h>

#include "agreement.h"
#include "test_scenes.h"

using namespace accelbench;

using test::random_soup;

TEST(BruteForce, AgreesWithEmbreeOnRandomSoup) {
    Scene scene = random_soup(500, 42);
    auto bf = make_accelerator("brute_force", {});
    bf->build(scene);
    test::expect_agrees_with_embree(scene, *bf, test::probe_rays(scene, 4000), "brute_force soup");
}

TEST(BruteForce, CountsEveryTrianglePerRay) {
    Scene scene = random_soup(37, 7);
    auto bf = make_accelerator("brute_force", {});
    bf->build(scene);
    auto rays = test::probe_rays(scene, 10);
    std::vector<Hit> hits(rays.size());
    std::vector<RayStats> stats(rays.size());
    bf->closest_hits(rays, hits, stats);
    for (const auto& s : stats) EXPECT_EQ(s.prim_tests, 37u);
}

TEST(BruteForce, RefusesLargeScenesUnlessForced) {
    Scene scene = random_soup(101, 3);
    auto bf = make_accelerator("brute_force", {{"max_triangles", "100"}});
    try {
        bf->build(scene);
        FAIL() << "expected a refusal";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("force=true"), std::string::npos) << e.what();
    }
    auto forced = make_accelerator("brute_force", {{"max_triangles", "100"}, {"force", "true"}});
    EXPECT_NO_THROW(forced->build(scene));
}

TEST(Registry, UnknownAcceleratorAndParameterAreErrors) {
    EXPECT_THROW(make_accelerator("octree", {}), ParamError);
    try {
        make_accelerator("brute_force", {{"max_prims", "4"}});
        FAIL();
    } catch (const ParamError& e) {
        EXPECT_NE(std::string(e.what()).find("has no parameter 'max_prims'"), std::string::npos) << e.what();
    }
    EXPECT_THROW(make_accelerator("embree", {{"quality", "ultra"}}), ParamError);
    EXPECT_THROW(make_accelerator("embree", {{"threads", "-1"}}), ParamError);
    EXPECT_THROW(make_accelerator("brute_force", {{"max_triangles", "1.5"}}), ParamError);
}
