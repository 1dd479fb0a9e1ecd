// The generators of the extreme-case catalogue, one per case (robustness_cases.h lists
// them); each builds its scene, its rays and what a correct implementation must answer.
#include "accelbench/verify/robustness_generators.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "accelbench/base/random.h"
#include "accelbench/verify/robustness_helpers.h"

namespace accelbench::robustness {

// Cases 1-3: a unit icosphere and the integer box [0, 4]^3, scaled then translated, with
// rays from interior points aimed exactly at every vertex and at points on every edge
// (its midpoint and quarter points as float computes them: exact for the box's integer
// coordinates, within rounding of the edge for the sphere). A closed mesh seen from
// inside has no gap: every such ray must hit. The two meshes are far apart so an inside
// ray of one cannot be caught by the other.
RobustnessCase closed_meshes(std::string id, std::string name, float scale, float offset) {
    RobustnessCase c;
    c.id = std::move(id);
    c.name = std::move(name);
    c.requirement =
        "closed meshes seen from inside: every ray aimed at a vertex or at a point on an edge hits (zero leaks "
        "for watertight structures; counted for the others); no NaN";
    WeldedMeshBuilder m;
    struct Part {
        Scene mesh;
        Vec3 shift;
        std::vector<Vec3> inside;
    };
    std::vector<Part> parts;
    parts.push_back({icosphere(2), {0, 0, 0}, {{0, 0, 0}, {0.25f, -0.125f, 0.375f}, {-0.5f, 0.25f, 0.125f}}});
    parts.push_back({grid_box(4), {4, 0, 0}, {{2, 2, 2}, {1.25f, 2.5f, 3.75f}, {0.5f, 0.5f, 0.5f}}});
    for (const Part& part : parts) {
        auto place = [&](Vec3 p) { return transform(p + part.shift, scale, offset); };
        for (const auto& t : part.mesh.triangles)
            m.triangle(place(part.mesh.vertices[t[0]]), place(part.mesh.vertices[t[1]]),
                       place(part.mesh.vertices[t[2]]));
    }
    c.scene = std::move(m.scene());
    // At large offsets rounding merges origins and targets (the sphere at 1e7 falls onto a
    // lattice): each distinct ray is traced once.
    std::set<std::tuple<float, float, float, float, float, float>> seen;
    for (const Part& part : parts) {
        auto place = [&](Vec3 p) { return transform(p + part.shift, scale, offset); };
        std::vector<Vec3> targets = part.mesh.vertices;
        for (auto [a, b] : edges(part.mesh)) {
            const Vec3 pa = part.mesh.vertices[a], pb = part.mesh.vertices[b];
            for (float f : {0.25f, 0.5f, 0.75f}) targets.push_back(pa + (pb - pa) * f);
        }
        for (Vec3 o : part.inside) {
            // Rounding at large offsets moves vertices (the sphere at 1e7, where the float
            // spacing is 1, collapses onto a lattice) and may leave an origin on the surface
            // or outside: only origins still strictly inside the rounded mesh count.
            const Vec3 org = place(o);
            if (!strictly_inside(c.scene, org)) continue;
            for (Vec3 t : targets) {
                const Vec3 dir = place(t) - org;
                if (dir == Vec3{0, 0, 0}) continue;  // the target rounded onto the origin
                if (!seen.insert({org.x, org.y, org.z, dir.x, dir.y, dir.z}).second) continue;
                add_ray(c, {org, 0.0f, dir, kInfinity}, kHitIfWatertight);
            }
        }
    }
    return c;
}

RobustnessCase origins_on_box_faces() {
    FloorRoof f = floor_and_roof(
        "4", "origins-on-box-faces",
        "axis-aligned rays whose origins lie exactly on bounding-box planes (the 0 * inf slab case) and which pass "
        "through the edge shared by two triangles hit one of them (watertight structures); rays along the outer "
        "boundary: no NaN");
    for (int line = 0; line <= f.n; ++line) {
        const bool inner = line > 0 && line < f.n;
        for (int j = 0; j < f.n; ++j) {
            const float along = float(j) + 0.5f, at = float(line);
            for (int axis = 0; axis < 2; ++axis) {
                const float x = axis == 0 ? at : along, y = axis == 0 ? along : at;
                const RayExpectation e = inner ? kHitIfWatertight : kAny;
                add_ray(f.c, {{x, y, 1.0f}, 0.0f, {0, 0, -1}, kInfinity}, e);  // to the floor
                add_ray(f.c, {{x, y, 1.0f}, 0.0f, {0, 0, 1}, kInfinity}, e);   // to the roof
                add_ray(f.c, {{x, y, -1.0f}, 0.0f, {0, 0, 1}, kInfinity}, e);  // floor from below
            }
        }
    }
    return f.c;
}

RobustnessCase signed_zero_directions() {
    FloorRoof f = floor_and_roof(
        "5", "signed-zero-directions",
        "rays whose zero direction components are +0.0 or -0.0 give the same answers: the triangle under/over a "
        "centroid (all structures), a hit through shared edges (watertight structures)");
    std::vector<std::pair<Vec3, Vec3>> down_up;
    for (float zx : {0.0f, -0.0f})
        for (float zy : {0.0f, -0.0f}) down_up.push_back({{zx, zy, -1}, {zx, zy, 1}});
    add_centroid_rays(f, down_up);
    for (int line = 1; line < f.n; ++line)
        for (float zx : {0.0f, -0.0f})
            for (float zy : {0.0f, -0.0f}) {
                add_ray(f.c, {{float(line), 1.5f, 1.0f}, 0.0f, {zx, zy, -1}, kInfinity}, kHitIfWatertight);
                add_ray(f.c, {{1.5f, float(line), 1.0f}, 0.0f, {zx, zy, 1}, kInfinity}, kHitIfWatertight);
            }
    return f.c;
}

RobustnessCase tiny_direction_components() {
    FloorRoof f = floor_and_roof(
        "6", "tiny-direction-components",
        "rays with tiny non-zero direction components (1e-40 denormal, 1e-20, 1e-15, 1e-11) aimed at a triangle's "
        "centroid hit that triangle: huge reciprocals must not become NaN or cull boxes");
    std::vector<std::pair<Vec3, Vec3>> down_up;
    for (float eps : {1e-40f, 1e-20f, 1e-15f, 1e-11f}) down_up.push_back({{eps, -eps, -1}, {-eps, 0.0f, 1}});
    add_centroid_rays(f, down_up);
    return f.c;
}

RobustnessCase grazing_rays() {
    FloorRoof f = floor_and_roof(
        "7", "grazing-rays",
        "rays parallel to a triangle's plane and 1 ulp off it miss; grazing rays crossing the plane at a centroid "
        "(slopes 1e-3, 1e-6) hit that triangle; rays inside the plane: no NaN (a zero determinant is a miss)");
    const float denorm = std::numeric_limits<float>::denorm_min();
    const float n = float(f.n);
    for (int j = 0; j < f.n; ++j) {
        const float y = float(j) + 0.375f;
        // Parallel, 1 ulp above and below the floor (z = 0) and the roof (z = 2).
        for (float z : {denorm, -denorm, std::nextafter(2.0f, 3.0f), std::nextafter(2.0f, 1.0f)}) {
            add_ray(f.c, {{-1.0f, y, z}, 0.0f, {1, 0, 0}, kInfinity}, kMiss);
            add_ray(f.c, {{n + 1, y, z}, 0.0f, {-1, 0.25f, 0}, kInfinity}, kMiss);
        }
        // In the planes.
        for (float z : {0.0f, 2.0f}) add_ray(f.c, {{-1.0f, y, z}, 0.0f, {1, 0, 0}, kInfinity}, kAny);
    }
    const uint32_t cells = 2 * uint32_t(f.n * f.n);
    for (uint32_t p = 0; p < cells; ++p) {
        const Vec3 c = centroid(f.c.scene, p);
        for (float slope : {1e-3f, 1e-6f}) {
            // From (c.x - 1, c.y, slope) along (1, 0, -slope): z reaches 0 exactly at c.
            add_ray(f.c, {{c.x - 1.0f, c.y, slope}, 0.0f, {1, 0, -slope}, kInfinity}, prim_is(f.floor_first + p));
            add_ray(f.c, {{c.x + 1.0f, c.y, 2.0f - slope}, 0.0f, {-1, 0, slope}, kInfinity}, prim_is(f.roof_first + p));
        }
    }
    return f.c;
}

RobustnessCase degenerate_triangles() {
    RobustnessCase c;
    c.id = "8";
    c.name = "degenerate-triangles";
    c.requirement =
        "zero-area triangles (collinear, coincident vertices, a single point) are never hit: axis-aligned rays "
        "through them reach the floor triangle below; needles (valid, 1e-6 wide) and oblique rays: no NaN";
    const int n = 4;
    WeldedMeshBuilder m;
    const uint32_t floor_first = add_grid(m, 2, 0.0f, n);
    std::vector<std::pair<float, float>> through;  // (dx, dy) inside a cell, on a degenerate triangle
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const float x = float(i), y = float(j), z = 1.0f;
            // Collinear (exact dyadic points on one line), off the floor's cell diagonals.
            m.unshared_triangle({x + 0.125f, y + 0.5f, z}, {x + 0.375f, y + 0.625f, z}, {x + 0.625f, y + 0.75f, z});
            // Two coincident vertices.
            m.unshared_triangle({x + 0.75f, y + 0.25f, z}, {x + 0.75f, y + 0.25f, z}, {x + 0.875f, y + 0.75f, z});
            // All three coincident.
            m.unshared_triangle({x + 0.5f, y + 0.125f, z}, {x + 0.5f, y + 0.125f, z}, {x + 0.5f, y + 0.125f, z});
            // Needle: valid, 1e-6 wide.
            m.unshared_triangle({x + 0.0625f, y + 0.9375f, z}, {x + 0.5625f, y + 0.9375f, z},
                                {x + 0.3125f, y + 0.9375f + 1e-6f, z});
        }
    through = {{0.375f, 0.625f}, {0.25f, 0.5625f}, {0.75f, 0.25f}, {0.8125f, 0.5f}, {0.5f, 0.125f}};
    c.scene = std::move(m.scene());
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            for (auto [dx, dy] : through) {
                const float x = float(i) + dx, y = float(j) + dy;
                add_ray(c, {{x, y, 2.0f}, 0.0f, {0, 0, -1}, kInfinity}, prim_is(grid_prim_at(floor_first, n, x, y)));
                add_ray(c, {{x - 0.5f, y + 0.25f, 2.0f}, 0.0f, {0.5f, -0.25f, -1}, kInfinity}, kAny);
            }
            add_ray(c, {{float(i) + 0.3125f, float(j) + 0.9375f + 2.5e-7f, 2.0f}, 0.0f, {0, 0, -1}, kInfinity}, kAny);
        }
    return c;
}

RobustnessCase copies_and_equal_centroids() {
    RobustnessCase c;
    c.id = "9";
    c.name = "copies-equal-centroids";
    c.requirement =
        "64 copies of one triangle (32 sharing vertices, 32 with their own) and 48 triangles whose bounds are all "
        "the same box (equal centroids): builders terminate with bounded depth; a ray at the copies hits one of "
        "them; rays through the box agree with the reference (informational), no NaN";
    WeldedMeshBuilder m;
    const Vec3 a{5, 0, 0}, b{6, 0, 0}, d{5, 1, 0};
    for (int i = 0; i < 32; ++i) m.triangle(a, b, d);
    for (int i = 0; i < 32; ++i) m.unshared_triangle(a, b, d);
    const uint32_t copies_last = m.count() - 1;
    // Triples of corners of [-1, 1]^3 whose bounds are the whole cube.
    std::vector<Vec3> corners;
    for (int k = 0; k < 8; ++k) corners.push_back({k & 1 ? 1.0f : -1.0f, k & 2 ? 1.0f : -1.0f, k & 4 ? 1.0f : -1.0f});
    for (int i = 0; i < 8; ++i)
        for (int j = i + 1; j < 8; ++j)
            for (int k = j + 1; k < 8; ++k) {
                Bounds3 bb(corners[i]);
                bb.extend(corners[j]);
                bb.extend(corners[k]);
                if (bb == Bounds3({-1, -1, -1}, {1, 1, 1})) m.triangle(corners[i], corners[j], corners[k]);
            }
    c.scene = std::move(m.scene());
    SplitMix64 draw(9);
    for (int i = 0; i < 64; ++i) {
        const float u = 0.05f + 0.4f * draw.uniform(), v = 0.05f + 0.4f * draw.uniform();
        add_ray(c, {{5 + u, v, 1}, 0.0f, {0, 0, -1}, kInfinity}, prim_range(0, copies_last));
        add_ray(c, {{5 + u, v, -1}, 0.0f, {0.01f, 0.02f, 1}, kInfinity}, prim_range(0, copies_last));
    }
    for (int i = 0; i < 256; ++i) {
        const Vec3 from = draw.unit_vector() * 4.0f;
        const Vec3 to = Vec3{draw.uniform(), draw.uniform(), draw.uniform()} * 1.6f - Vec3{0.8f, 0.8f, 0.8f};
        add_ray(c, {from, 0.0f, to - from, kInfinity}, kAny);
    }
    return c;
}

RobustnessCase flat_scene() {
    RobustnessCase c;
    c.id = "10";
    c.name = "flat-scene";
    c.requirement =
        "every vertex has x = 2 (the scene's bounds have zero width): builders must not divide by the zero "
        "extent; rays along +-x at a centroid, and oblique rays through it, hit that triangle; in-plane rays: "
        "no NaN";
    const int n = 8;
    WeldedMeshBuilder m;
    add_grid(m, 0, 2.0f, n);
    c.scene = std::move(m.scene());
    const uint32_t count = 2 * uint32_t(n * n);
    for (uint32_t p = 0; p < count; ++p) {
        const Vec3 ct = centroid(c.scene, p);
        add_ray(c, {{1.0f, ct.y, ct.z}, 0.0f, {1, 0, 0}, kInfinity}, prim_is(p));
        add_ray(c, {{3.0f, ct.y, ct.z}, 0.0f, {-1, 0, 0}, kInfinity}, prim_is(p));
        const Vec3 o{0.0f, ct.y + 0.3f, ct.z - 0.2f};
        add_ray(c, {o, 0.0f, ct - o, kInfinity}, prim_is(p));
    }
    for (int j = 0; j < n; ++j) add_ray(c, {{2.0f, -1.0f, float(j) + 0.3f}, 0.0f, {0, 1, 0}, kInfinity}, kAny);
    return c;
}

RobustnessCase cluster_and_outlier() {
    RobustnessCase c;
    c.id = "11";
    c.name = "cluster-and-outlier";
    c.requirement =
        "three layers of 512 triangles within 1e-3 plus one triangle at 1e6 (the cluster falls into one Morton "
        "cell): builders terminate with bounded depth; rays at the centroids of the bottom and top layers and at "
        "the outlier hit those triangles";
    const int n = 16;
    const float cell = 1e-3f / float(n);
    WeldedMeshBuilder m;
    uint32_t layer_first[3];
    for (int l = 0; l < 3; ++l) layer_first[l] = add_grid(m, 2, float(l) * 1e-3f, n, cell);
    const uint32_t outlier = m.triangle(Vec3{1e6f, 1e6f, 1e6f}, Vec3{1e6f + 1, 1e6f, 1e6f}, Vec3{1e6f, 1e6f + 1, 1e6f});
    c.scene = std::move(m.scene());
    const uint32_t per_layer = 2 * uint32_t(n * n);
    for (uint32_t p = 0; p < per_layer; ++p) {
        const Vec3 bottom = centroid(c.scene, layer_first[0] + p), top = centroid(c.scene, layer_first[2] + p);
        add_ray(c, {{bottom.x, bottom.y, -1e-3f}, 0.0f, {0, 0, 1}, kInfinity}, prim_is(layer_first[0] + p));
        add_ray(c, {{top.x, top.y, 3e-3f}, 0.0f, {0, 0, -1}, kInfinity}, prim_is(layer_first[2] + p));
    }
    const Vec3 o = centroid(c.scene, outlier);
    add_ray(c, {{o.x, o.y, o.z + 10}, 0.0f, {0, 0, -1}, kInfinity}, prim_is(outlier));
    add_ray(c, {{0.5e-3f, 0.5e-3f, -1}, 0.0f, o - Vec3{0.5e-3f, 0.5e-3f, -1}, kInfinity}, kAny);
    return c;
}

RobustnessCase coplanar_split_planes() {
    RobustnessCase c;
    c.id = "12";
    c.name = "coplanar-split-planes";
    c.requirement =
        "grids of triangles lying in the planes x, y, z = 0..3 (every candidate split plane holds flat "
        "triangles): a ray perpendicular to a triangle at its centroid, from either side, returns that triangle";
    const int n = 4;
    WeldedMeshBuilder m;
    std::vector<std::pair<uint32_t, int>> planes;  // first triangle, axis
    for (int axis = 0; axis < 3; ++axis)
        for (int level = 0; level < 4; ++level) planes.push_back({add_grid(m, axis, float(level), n), axis});
    c.scene = std::move(m.scene());
    const uint32_t per_plane = 2 * uint32_t(n * n);
    for (auto [first, axis] : planes)
        for (uint32_t p = first; p < first + per_plane; ++p) {
            const Vec3 ct = centroid(c.scene, p);
            Vec3 dir{0, 0, 0};
            dir[axis] = 1;
            add_ray(c, {ct - dir * 0.5f, 0.0f, dir, kInfinity}, prim_is(p));
            add_ray(c, {ct + dir * 0.5f, 0.0f, -dir, kInfinity}, prim_is(p));
        }
    return c;
}

RobustnessCase overlapping_coplanar() {
    RobustnessCase c;
    c.id = "13";
    c.name = "overlapping-coplanar";
    c.requirement =
        "32 coplanar triangles (z = 1) that all cover the unit disk: every ray into the disk hits one of them at "
        "t = 1, the same one on every trace and every rebuild (the reference returns the smallest id)";
    WeldedMeshBuilder m;
    for (int k = 0; k < 32; ++k) {
        const float phase = float(k) * 0.0654f, radius = 2.5f + 0.01f * float(k);
        Vec3 p[3];
        for (int i = 0; i < 3; ++i) {
            const float a = phase + float(i) * 2.0f * std::numbers::pi_v<float> / 3.0f;
            p[i] = {radius * std::cos(a), radius * std::sin(a), 1.0f};
        }
        m.unshared_triangle(p[0], p[1], p[2]);
    }
    c.scene = std::move(m.scene());
    for (float x = -0.875f; x <= 0.875f; x += 0.125f)
        for (float y = -0.875f; y <= 0.875f; y += 0.125f) {
            if (x * x + y * y >= 1.0f) continue;
            add_ray(c, {{x, y, 2.0f}, 0.0f, {0, 0, -1}, kInfinity}, prim_range(0, 31));
            add_ray(c, {{x - 0.25f, y, 0.0f}, 0.0f, {0.25f, 0, 1}, kInfinity}, prim_range(0, 31));
        }
    return c;
}

// Case 14: a valid 4 x 4 floor plus one bad face with id 5 (or an unused bad vertex):
// every variant is rejected.
RobustnessCase bad_input(std::string id, std::string name, std::string requirement, int variant) {
    RobustnessCase c;
    c.id = std::move(id);
    c.name = std::move(name);
    c.requirement = std::move(requirement);
    const int n = 4;
    WeldedMeshBuilder m;
    add_grid(m, 2, 0.0f, n);
    Scene& s = m.scene();
    const uint32_t bad = 5;
    const uint32_t v = uint32_t(s.vertices.size());
    switch (variant) {
        case 0: s.vertices.push_back({kNaN, 0, 0}); break;
        case 1: s.vertices.push_back({0, kInfinity, 0}); break;
        case 2: s.vertices.push_back({0, 0, 2e19f}); break;
        default: s.vertices.push_back({1, 1, 1}); break;
    }
    if (variant <= 2) s.triangles[bad][1] = v;                 // a face uses the bad vertex
    if (variant == 3) s.triangles[bad][2] = v + 7;             // an index past the end
    if (variant == 4) s.vertices.back() = {kNaN, kNaN, kNaN};  // unused by any face
    c.scene = std::move(s);
    // A bad vertex is named as the vertex (used or not), an index past the end as the face.
    c.rejection_mentions = variant == 3 ? "face 5" : "vertex " + std::to_string(v);
    return c;
}

RobustnessCase invalid_rays() {
    FloorRoof f = floor_and_roof(
        "15", "invalid-rays",
        "rays with a NaN or infinite origin or direction component, a zero direction, a NaN tmin or tmax or an "
        "empty interval (tmin > tmax, tmin = +inf, tmax = -inf) hit nothing (any-hit included); tmin = -0 and "
        "tmax = inf are ordinary; an origin on a triangle (t = tmin): no NaN");
    const Vec3 c = centroid(f.c.scene, f.floor_first + 5);
    const uint32_t below = f.floor_first + 5;
    const Vec3 o{c.x, c.y, 1.0f}, down{0, 0, -1};
    // Ordinary.
    add_ray(f.c, {o, -0.0f, down, kInfinity}, prim_is(below));
    add_ray(f.c, {o, 0.0f, down, kInfinity}, prim_is(below));
    add_ray(f.c, {o, -0.0f, down, 1.5f}, prim_is(below));
    // Origin on the floor: a hit at t = tmin = 0. Ours count it (the interval is [tmin,
    // tmax)), Embree does not (its interval is (tnear, tfar]): a convention, not an error.
    add_ray(f.c, {{c.x, c.y, 0.0f}, -0.0f, {0, 0, 1}, kInfinity}, kAny);
    add_ray(f.c, {{c.x, c.y, 0.0f}, 0.0f, {0, 0, 1}, kInfinity}, kAny);
    // Invalid.
    const float inf = kInfinity;
    for (Vec3 bad_o : {Vec3{kNaN, c.y, 1}, Vec3{c.x, kNaN, 1}, Vec3{c.x, c.y, kNaN}, Vec3{inf, c.y, 1},
                       Vec3{c.x, -inf, 1}, Vec3{c.x, c.y, inf}})
        add_ray(f.c, {bad_o, 0.0f, down, kInfinity}, kMiss);
    for (Vec3 bad_d : {Vec3{kNaN, 0, -1}, Vec3{0, kNaN, -1}, Vec3{0, 0, kNaN}, Vec3{inf, 0, -1}, Vec3{0, 0, -inf},
                       Vec3{0, 0, 0}, Vec3{-0.0f, 0, -0.0f}, Vec3{kNaN, kNaN, kNaN}})
        add_ray(f.c, {o, 0.0f, bad_d, kInfinity}, kMiss);
    add_ray(f.c, {o, kNaN, down, kInfinity}, kMiss);
    add_ray(f.c, {o, 0.0f, down, kNaN}, kMiss);
    add_ray(f.c, {o, 2.0f, down, 1.0f}, kMiss);
    add_ray(f.c, {o, inf, down, inf}, kMiss);
    add_ray(f.c, {o, 0.0f, down, -inf}, kMiss);
    return f.c;
}

RobustnessCase nested_shells() {
    RobustnessCase c;
    c.id = "16";
    c.name = "nested-shells";
    c.requirement =
        "three concentric spheres 4e-5 apart (about 670 float ulps): rays from the centre hit the innermost "
        "shell, rays from outside the outermost";
    const Scene sphere = icosphere(2);
    WeldedMeshBuilder m;
    const uint32_t per_shell = uint32_t(sphere.triangle_count());
    for (int s = 0; s < 3; ++s) {
        const float r = 1.0f + 4e-5f * float(s);
        for (const auto& t : sphere.triangles)
            m.unshared_triangle(sphere.vertices[t[0]] * r, sphere.vertices[t[1]] * r, sphere.vertices[t[2]] * r);
    }
    c.scene = std::move(m.scene());
    SplitMix64 draw(16);
    for (int i = 0; i < 400; ++i)
        add_ray(c, {{0, 0, 0}, 0.0f, draw.unit_vector(), kInfinity}, prim_range(0, per_shell - 1));
    for (int i = 0; i < 400; ++i) {
        const Vec3 from = draw.unit_vector() * 3.0f, to = draw.unit_vector() * 0.3f;
        add_ray(c, {from, 0.0f, to - from, kInfinity}, prim_range(2 * per_shell, 3 * per_shell - 1));
    }
    return c;
}

RobustnessCase distant_camera() {
    RobustnessCase c;
    c.id = "17";
    c.name = "distant-camera";
    c.requirement =
        "a closed unit sphere seen from 1e6 away: rays aimed within 0.5 of its centre hit it (the float direction "
        "is off by ~0.1 there, and a non-watertight test leaks through edges within ~0.1: required of watertight "
        "structures); t error against the reference is reported; no NaN";
    c.scene = icosphere(3);
    const Vec3 eye{6e5f, 3e5f, 7e5f};
    for (float u = -0.5f; u <= 0.5f; u += 0.0625f)
        for (float v = -0.5f; v <= 0.5f; v += 0.0625f) {
            if (u * u + v * v > 0.25f) continue;
            add_ray(c, {eye, 0.0f, normalize(Vec3{u, v, 0} - eye), kInfinity}, kHitIfWatertight);
        }
    for (int k = 0; k < 64; ++k) {  // around the silhouette: informational
        const float a = float(k) * 0.0981f;
        add_ray(c, {eye, 0.0f, normalize(Vec3{std::cos(a), std::sin(a), 0} - eye), kInfinity}, kAny);
    }
    return c;
}

RobustnessCase deep_tree() {
    RobustnessCase c;
    c.id = "18";
    c.name = "deep-tree";
    c.requirement =
        "300 triangles in a geometric progression (position and size 0.9^i, down to 2e-15): a builder that "
        "splits off one triangle per level would make a 300-deep tree; depth must stay within the structure's "
        "limit and traversal must not overflow its stack; a ray at each centroid hits that triangle";
    WeldedMeshBuilder m;
    float x = 1.0f;
    for (int i = 0; i < 300; ++i, x *= 0.9f) {
        const float s = 0.1f * x;
        m.unshared_triangle({x, x, x}, {x + s, x, x}, {x, x + s, x});
    }
    c.scene = std::move(m.scene());
    for (uint32_t p = 0; p < c.scene.triangle_count(); ++p) {
        const Vec3 ct = centroid(c.scene, p);
        add_ray(c, {{ct.x, ct.y, 2.0f}, 0.0f, {0, 0, -1}, kInfinity}, prim_is(p));
    }
    return c;
}

}  // namespace accelbench::robustness
