#include "accelbench/scene/mesh_transform.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

using namespace accelbench;

namespace {

// The regular icosahedron: 12 vertices, 20 faces, closed and consistently oriented.
Scene icosahedron() {
    Scene s;
    s.name = "icosahedron";
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    s.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                  {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    s.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                   {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                   {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    s.finalize();
    return s;
}

// Closed: every undirected edge is used by exactly two triangles, once in each direction
// (a consistently oriented 2-manifold without boundary).
bool is_closed(const Scene& s) {
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (const auto& t : s.triangles)
        for (int k = 0; k < 3; ++k) ++directed[{t[size_t(k)], t[size_t((k + 1) % 3)]}];
    for (const auto& [e, n] : directed) {
        if (n != 1) return false;
        auto back = directed.find({e.second, e.first});
        if (back == directed.end() || back->second != 1) return false;
    }
    return true;
}

}  // namespace

TEST(LoopSubdivide, FourTrianglesPerLevelAndStaysClosed) {
    const Scene ico = icosahedron();
    for (int levels = 1; levels <= 3; ++levels) {
        MeshTransformInfo info;
        Scene s = loop_subdivide(ico, levels, &info);
        const size_t expected = 20u << (2 * levels);
        EXPECT_EQ(s.triangle_count(), expected) << levels;
        EXPECT_EQ(info.triangles, expected);
        EXPECT_EQ(info.refused_faces, 0u);
        // Euler: a closed genus-0 triangle mesh has V = F/2 + 2.
        EXPECT_EQ(s.vertex_count(), expected / 2 + 2) << levels;
        EXPECT_TRUE(is_closed(s)) << levels;
    }
}

TEST(LoopSubdivide, SmoothsTowardTheSphere) {
    // Loop's masks shrink a convex mesh: every new vertex lies inside the original's
    // circumscribed sphere, and the result is rounder than the icosahedron.
    const Scene ico = icosahedron();
    const float r0 = std::sqrt(ico.vertices[0].x * ico.vertices[0].x + ico.vertices[0].y * ico.vertices[0].y);
    Scene s = loop_subdivide(ico, 2);
    float lo = 1e30f, hi = 0;
    for (const Vec3& v : s.vertices) {
        const float r = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
        lo = std::min(lo, r);
        hi = std::max(hi, r);
    }
    EXPECT_LT(hi, r0 + 1e-4f);
    EXPECT_LT(hi - lo, 0.1f * hi);
}

TEST(Decimate, ReachesTheTargetAndStaysClosed) {
    const Scene fine = loop_subdivide(icosahedron(), 3);  // 1280 triangles
    for (size_t target : {800u, 300u, 100u}) {
        MeshTransformInfo info;
        Scene s = decimate(fine, target, &info);
        // An edge collapse removes two triangles of a closed mesh: the target or one less.
        EXPECT_LE(s.triangle_count(), target);
        EXPECT_GE(s.triangle_count() + 2, target);
        EXPECT_EQ(info.source_triangles, 1280u);
        EXPECT_EQ(info.refused_faces, 0u);
        EXPECT_TRUE(is_closed(s)) << target;
        EXPECT_EQ(s.vertex_count(), s.triangle_count() / 2 + 2) << target;
    }
}

TEST(Decimate, IsDeterministic) {
    const Scene fine = loop_subdivide(icosahedron(), 3);
    Scene a = decimate(fine, 200), b = decimate(fine, 200);
    ASSERT_EQ(a.triangles, b.triangles);
    ASSERT_EQ(a.vertices.size(), b.vertices.size());
    for (size_t i = 0; i < a.vertices.size(); ++i) {
        EXPECT_EQ(a.vertices[i].x, b.vertices[i].x);
        EXPECT_EQ(a.vertices[i].y, b.vertices[i].y);
        EXPECT_EQ(a.vertices[i].z, b.vertices[i].z);
    }
}

TEST(Decimate, CountsNonManifoldFacesItRefuses) {
    // The icosahedron plus a fin: a third face on the edge (0, 11) makes it non-manifold,
    // which a half-edge mesh cannot hold.
    Scene s = icosahedron();
    s.vertices.push_back({-3, 3, 3});
    s.triangles.push_back({0, 11, 12});
    s.finalize();
    MeshTransformInfo info;
    Scene d = decimate(s, 16, &info);
    EXPECT_EQ(info.refused_faces, 1u);
    EXPECT_EQ(info.source_triangles, 21u);
    EXPECT_LE(d.triangle_count(), 16u);
    EXPECT_TRUE(is_closed(d));
}

TEST(MeshTransform, RejectsBadArguments) {
    const Scene ico = icosahedron();
    EXPECT_THROW(decimate(ico, 0), std::invalid_argument);
    EXPECT_THROW(decimate(ico, 20), std::invalid_argument);
    EXPECT_THROW(loop_subdivide(ico, 0), std::invalid_argument);
    EXPECT_THROW(loop_subdivide(ico, 5), std::invalid_argument);
}
