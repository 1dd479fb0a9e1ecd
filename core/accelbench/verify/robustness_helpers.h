// The building blocks of the extreme-case catalogue's generators (robustness_generators.cpp):
// welded meshes, grids on axis-aligned planes, closed test meshes and their edges, the
// inside test, and the rays with their expectations.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numbers>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "accelbench/verify/robustness_cases.h"

namespace accelbench::robustness {

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Builds a triangle mesh whose vertices are shared by exact position, so neighbouring
// triangles reference the same vertex indices (what makes a mesh closed).
class WeldedMeshBuilder {
public:
    uint32_t vertex(Vec3 p) {
        auto key = std::make_tuple(bits(p.x), bits(p.y), bits(p.z));
        auto [it, inserted] = index_.try_emplace(key, uint32_t(scene_.vertices.size()));
        if (inserted) scene_.vertices.push_back(p);
        return it->second;
    }
    uint32_t triangle(Vec3 a, Vec3 b, Vec3 c) { return triangle(vertex(a), vertex(b), vertex(c)); }
    uint32_t triangle(uint32_t a, uint32_t b, uint32_t c) {
        scene_.triangles.push_back({a, b, c});
        return uint32_t(scene_.triangles.size() - 1);
    }
    // A triangle with its own vertex copies (not shared with anything).
    uint32_t unshared_triangle(Vec3 a, Vec3 b, Vec3 c) {
        const uint32_t i = uint32_t(scene_.vertices.size());
        scene_.vertices.insert(scene_.vertices.end(), {a, b, c});
        return triangle(i, i + 1, i + 2);
    }
    uint32_t count() const { return uint32_t(scene_.triangles.size()); }
    Scene& scene() { return scene_; }

private:
    static uint32_t bits(float f) {
        if (f == 0.0f) f = 0.0f;  // +0 and -0 are one position
        uint32_t u;
        std::memcpy(&u, &f, sizeof u);
        return u;
    }
    Scene scene_;
    std::map<std::tuple<uint32_t, uint32_t, uint32_t>, uint32_t> index_;
};

// Point on an axis-aligned plane: coordinate `axis` fixed at `level`, (u, v) the other
// two in increasing axis order.
inline Vec3 on_plane(int axis, float level, float u, float v) {
    if (axis == 0) return {level, u, v};
    if (axis == 1) return {u, level, v};
    return {u, v, level};
}

// An n x n grid of unit cells on an axis-aligned plane, origin at (0, 0), each cell split
// along its diagonal into triangle 0 (below the diagonal, fu > fv) and 1 (above). Returns
// the id of the first triangle; cell (i, j) holds first + 2 (j n + i) + {0, 1}.
inline uint32_t add_grid(WeldedMeshBuilder& m, int axis, float level, int n, float cell = 1.0f, Vec3 offset = {}) {
    const uint32_t first = m.count();
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            auto p = [&](int di, int dj) { return on_plane(axis, level, (i + di) * cell, (j + dj) * cell) + offset; };
            m.triangle(p(0, 0), p(1, 0), p(1, 1));
            m.triangle(p(0, 0), p(1, 1), p(0, 1));
        }
    return first;
}

// The grid triangle containing plane point (u, v) (not on a cell edge or diagonal).
inline uint32_t grid_prim_at(uint32_t first, int n, float u, float v, float cell = 1.0f) {
    const int i = int(std::floor(u / cell)), j = int(std::floor(v / cell));
    const float fu = u / cell - float(i), fv = v / cell - float(j);
    return first + 2 * uint32_t(j * n + i) + (fu > fv ? 0 : 1);
}

inline Vec3 centroid(const Scene& s, uint32_t prim) {
    return (s.vertex(prim, 0) + s.vertex(prim, 1) + s.vertex(prim, 2)) / 3.0f;
}

// Icosahedron subdivided `levels` times, vertices on the unit sphere, faces outward.
inline Scene icosphere(int levels) {
    const float g = (1.0f + std::sqrt(5.0f)) / 2.0f;
    std::vector<Vec3> v = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                           {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
    for (auto& p : v) p = normalize(p);
    std::vector<std::array<uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                              {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                              {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                              {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            auto key = std::minmax(a, b);
            auto [it, inserted] = mid.try_emplace({key.first, key.second}, uint32_t(v.size()));
            if (inserted) v.push_back(normalize(v[a] + v[b]));
            return it->second;
        };
        std::vector<std::array<uint32_t, 3>> next;
        for (auto [a, b, c] : f) {
            const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
        }
        f = std::move(next);
    }
    Scene s;
    s.vertices = std::move(v);
    s.triangles = std::move(f);
    return s;
}

// The surface of the cube [0, n]^3 as a closed mesh of integer-coordinate unit squares.
inline Scene grid_box(int n) {
    WeldedMeshBuilder m;
    const float fn = float(n);
    for (int axis = 0; axis < 3; ++axis)
        for (float level : {0.0f, fn}) add_grid(m, axis, level, n);
    // Orient every face outward (the box is convex), so the winding number is defined.
    Scene& s = m.scene();
    const Vec3 centre{fn / 2, fn / 2, fn / 2};
    for (auto& t : s.triangles) {
        const Vec3 a = s.vertices[t[0]], b = s.vertices[t[1]], c = s.vertices[t[2]];
        if (dot(cross(b - a, c - a), a - centre) < 0) std::swap(t[1], t[2]);
    }
    return std::move(s);
}

// Unique undirected edges of a mesh.
inline std::vector<std::pair<uint32_t, uint32_t>> edges(const Scene& s) {
    std::vector<std::pair<uint32_t, uint32_t>> e;
    for (const auto& t : s.triangles)
        for (int k = 0; k < 3; ++k) e.push_back(std::minmax(t[k], t[(k + 1) % 3]));
    std::sort(e.begin(), e.end());
    e.erase(std::unique(e.begin(), e.end()), e.end());
    return e;
}

// Whether p lies strictly inside a closed mesh: its winding number, the sum of the solid
// angles of the triangles seen from p over 4 pi (Van Oosterom and Strackee 1983), is a
// non-zero integer. A point on the surface gets a half-integer (the triangle it lies on
// subtends 2 pi or 0), so "within 1e-3 of a non-zero integer" excludes it. Evaluated in
// double with coordinates relative to p.
inline bool strictly_inside(const Scene& mesh, Vec3 p) {
    double total = 0.0;
    for (const auto& t : mesh.triangles) {
        double q[3][3], len[3];
        for (int k = 0; k < 3; ++k) {
            const Vec3 v = mesh.vertices[t[k]];
            q[k][0] = double(v.x) - p.x;
            q[k][1] = double(v.y) - p.y;
            q[k][2] = double(v.z) - p.z;
            len[k] = std::sqrt(q[k][0] * q[k][0] + q[k][1] * q[k][1] + q[k][2] * q[k][2]);
        }
        auto dot3 = [&](int i, int j) { return q[i][0] * q[j][0] + q[i][1] * q[j][1] + q[i][2] * q[j][2]; };
        const double det = q[0][0] * (q[1][1] * q[2][2] - q[1][2] * q[2][1]) -
            q[0][1] * (q[1][0] * q[2][2] - q[1][2] * q[2][0]) + q[0][2] * (q[1][0] * q[2][1] - q[1][1] * q[2][0]);
        const double den = len[0] * len[1] * len[2] + dot3(0, 1) * len[2] + dot3(0, 2) * len[1] + dot3(1, 2) * len[0];
        total += 2.0 * std::atan2(det, den);
    }
    const double w = total / (4.0 * std::numbers::pi);
    return std::fabs(w - std::round(w)) < 1e-3 && std::round(w) != 0.0;
}

inline Vec3 transform(Vec3 p, float scale, float offset) { return p * scale + Vec3{offset, offset, offset}; }

inline void add_ray(RobustnessCase& c, Ray r, RayExpectation e) {
    c.rays.push_back(r);
    c.expect.push_back(e);
}

inline RayExpectation prim_range(uint32_t lo, uint32_t hi) { return {Expect::Prim, lo, hi, false}; }
inline RayExpectation prim_is(uint32_t p) { return prim_range(p, p); }
inline constexpr RayExpectation kAny{Expect::Any, 0, 0, false};
inline constexpr RayExpectation kMiss{Expect::Miss, 0, 0, false};
inline constexpr RayExpectation kHit{Expect::Hit, 0, 0, false};
inline constexpr RayExpectation kHitIfWatertight{Expect::Hit, 0, 0, true};

// A floor grid (z = 0) and a roof grid (z = 2), n x n unit cells each: the scene of cases
// 4-7 and 15. Floor triangles are [0, 2n^2), the roof's the same cells plus 2n^2.
struct FloorRoof {
    RobustnessCase c;
    int n;
    uint32_t floor_first, roof_first;
};

inline FloorRoof floor_and_roof(std::string id, std::string name, std::string requirement, int n = 4) {
    FloorRoof f;
    f.c.id = std::move(id);
    f.c.name = std::move(name);
    f.c.requirement = std::move(requirement);
    f.n = n;
    WeldedMeshBuilder m;
    f.floor_first = add_grid(m, 2, 0.0f, n);
    f.roof_first = add_grid(m, 2, 2.0f, n);
    f.c.scene = std::move(m.scene());
    return f;
}

// From height 1, between floor and roof, through every cell's centroid: for each (down,
// up) direction pair one ray that must hit the floor triangle there and one the roof's.
inline void add_centroid_rays(FloorRoof& f, const std::vector<std::pair<Vec3, Vec3>>& down_up) {
    const uint32_t cells = 2 * uint32_t(f.n * f.n);
    for (uint32_t p = 0; p < cells; ++p) {
        const Vec3 c = centroid(f.c.scene, p);
        for (auto [down, up] : down_up) {
            add_ray(f.c, {{c.x, c.y, 1.0f}, 0.0f, down, kInfinity}, prim_is(f.floor_first + p));
            add_ray(f.c, {{c.x, c.y, 1.0f}, 0.0f, up, kInfinity}, prim_is(f.roof_first + p));
        }
    }
}

}  // namespace accelbench::robustness
