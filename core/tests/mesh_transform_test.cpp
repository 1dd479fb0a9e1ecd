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
        EXPECT_EQ(info.detached_faces, 0u);
        EXPECT_EQ(info.degenerate_faces, 0u);
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
        EXPECT_EQ(info.detached_faces, 0u);
        EXPECT_EQ(info.degenerate_faces, 0u);
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

// Twice the area of triangle i.
float double_area(const Scene& s, size_t i) {
    const Vec3 a = s.vertex(uint32_t(i), 0), b = s.vertex(uint32_t(i), 1), c = s.vertex(uint32_t(i), 2);
    const Vec3 n = cross(b - a, c - a);
    return std::sqrt(dot(n, n));
}

// The triangles of `s` with a corner at `p`, and the rest as a scene of their own.
size_t triangles_at(const Scene& s, Vec3 p) {
    size_t n = 0;
    for (size_t i = 0; i < s.triangle_count(); ++i)
        for (int k = 0; k < 3; ++k) {
            const Vec3 v = s.vertex(uint32_t(i), k);
            if (v.x == p.x && v.y == p.y && v.z == p.z) {
                ++n;
                break;
            }
        }
    return n;
}

Scene without_triangles_at(const Scene& s, Vec3 p) {
    Scene rest;
    rest.vertices = s.vertices;
    for (size_t i = 0; i < s.triangle_count(); ++i) {
        bool at = false;
        for (int k = 0; k < 3; ++k) {
            const Vec3 v = s.vertex(uint32_t(i), k);
            at |= v.x == p.x && v.y == p.y && v.z == p.z;
        }
        if (!at) rest.triangles.push_back(s.triangles[i]);
    }
    return rest;
}

// Three triangles on the edge (0, 1): a non-manifold fan, which a half-edge mesh cannot
// hold as it is.
Scene fan() {
    Scene s;
    s.name = "fan";
    s.vertices = {{0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, {0.5f, -1, 0}, {0.5f, 0, 1}};
    s.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
    s.finalize();
    return s;
}

TEST(LoopSubdivide, KeepsEveryFaceOfANonManifoldFan) {
    for (int levels = 1; levels <= 3; ++levels) {
        MeshTransformInfo info;
        const Scene s = loop_subdivide(fan(), levels, &info);
        const size_t expected = 3u << (2 * levels);
        EXPECT_EQ(s.triangle_count(), expected) << levels;
        EXPECT_EQ(info.triangles, expected);
        EXPECT_EQ(info.source_triangles, 3u);
        EXPECT_EQ(info.detached_faces, 1u);  // the third face on the edge
        EXPECT_EQ(info.degenerate_faces, 0u);
        // The detached face (in the plane y = 0, toward z) is subdivided in its own plane,
        // into a quarter of the triangles.
        size_t upright = 0;
        for (size_t i = 0; i < s.triangle_count(); ++i) {
            EXPECT_GT(double_area(s, i), 0.0f) << i;
            bool in_plane = true;
            for (int k = 0; k < 3; ++k) in_plane &= s.vertex(uint32_t(i), k).y == 0.0f;
            upright += in_plane &&
                (s.vertex(uint32_t(i), 0).z > 0 || s.vertex(uint32_t(i), 1).z > 0 || s.vertex(uint32_t(i), 2).z > 0);
        }
        EXPECT_EQ(upright, expected / 3) << levels;
    }
}

TEST(LoopSubdivide, KeepsAFaceWithARepeatedCorner) {
    // A face with a repeated corner is no half-edge face; with its own copies of its corners
    // it is a zero-area face that subdivides into zero-area faces.
    Scene s = icosahedron();
    s.triangles.push_back({0, 0, 5});
    s.finalize();
    MeshTransformInfo info;
    const Scene d = loop_subdivide(s, 2, &info);
    EXPECT_EQ(d.triangle_count(), 21u * 16u);
    EXPECT_EQ(info.degenerate_faces, 1u);
    EXPECT_EQ(info.detached_faces, 0u);
    // On the segment from vertex 0 to vertex 5 up to float rounding (the masks are computed
    // in double); the icosahedron's faces have twice-areas of 3.46 before subdivision.
    size_t zero = 0;
    for (size_t i = 0; i < d.triangle_count(); ++i) zero += double_area(d, i) < 1e-5f;
    EXPECT_EQ(zero, 16u);
}

TEST(Decimate, KeepsTheNonManifoldFaces) {
    // The icosahedron plus a fin: a third face on the edge (0, 11) makes it non-manifold.
    // The fin is detached (its own copies of its corners) and, a lone triangle, never
    // collapsed: it is in the result, inside the target; the rest is decimated and closed.
    Scene s = icosahedron();
    const Vec3 apex{-3, 3, 3};
    s.vertices.push_back(apex);
    s.triangles.push_back({0, 11, 12});
    s.triangles.push_back({5, 5, 1});  // and a face with a repeated corner
    s.finalize();
    MeshTransformInfo info;
    const Scene d = decimate(s, 16, &info);
    EXPECT_EQ(info.detached_faces, 1u);
    EXPECT_EQ(info.degenerate_faces, 1u);
    EXPECT_EQ(info.source_triangles, 22u);
    EXPECT_EQ(info.triangles, d.triangle_count());
    EXPECT_LE(d.triangle_count(), 16u);
    EXPECT_EQ(triangles_at(d, apex), 1u);
    size_t zero = 0;
    for (size_t i = 0; i < d.triangle_count(); ++i) zero += double_area(d, i) == 0.0f;
    EXPECT_EQ(zero, 1u);  // the face with a repeated corner, kept
    Scene rest = without_triangles_at(d, apex);
    rest.triangles.erase(std::remove_if(rest.triangles.begin(), rest.triangles.end(),
                                        [&](const auto& t) {
                                            const Vec3 a = rest.vertices[t[0]], b = rest.vertices[t[1]],
                                                       c = rest.vertices[t[2]];
                                            const Vec3 n = cross(b - a, c - a);
                                            return dot(n, n) == 0.0f;
                                        }),
                         rest.triangles.end());
    EXPECT_EQ(rest.triangle_count(), d.triangle_count() - 2);
    EXPECT_TRUE(is_closed(rest));
}

TEST(MeshTransform, RejectsBadArguments) {
    const Scene ico = icosahedron();
    EXPECT_THROW(decimate(ico, 0), std::invalid_argument);
    EXPECT_THROW(decimate(ico, 20), std::invalid_argument);
    EXPECT_THROW(loop_subdivide(ico, 0), std::invalid_argument);
    EXPECT_THROW(loop_subdivide(ico, 5), std::invalid_argument);
}
