// The one ray/triangle test every structure of ours uses: watertight intersection
// (Woop, Benthin, Wald 2013, "Watertight Ray/Triangle Intersection", JCGT 2(1)).
//
// Why this test: a ray through an edge shared by two triangles must hit at least one of
// them. Moeller-Trumbore can miss both because each triangle's edge test rounds on its
// own; the watertight test shears the triangle into ray space once per ray, evaluates the
// three 2D edge functions from the same sheared vertices, and falls back to double
// precision when an edge function is exactly zero, so neighbours agree on the shared edge.
#pragma once

#include <cmath>
#include <limits>

#include "accelbench/base/geometry.h"

namespace accelbench {

// Per-ray shear constants (section 3 of the paper). Computed once per ray, reused for
// every triangle the traversal tests.
struct WatertightRay {
    Vec3 org;
    int kx = 0, ky = 1, kz = 2;  // permutation: kz is the dominant direction axis
    float sx = 0, sy = 0, sz = 0;
    bool valid = false;  // is_valid_ray(): invalid rays hit nothing

    explicit WatertightRay(const Ray& r) : org(r.org) {
        Vec3 ad{std::fabs(r.dir.x), std::fabs(r.dir.y), std::fabs(r.dir.z)};
        valid = is_valid_ray(r);
        if (!valid) return;
        kz = max_axis(ad);
        kx = kz == 2 ? 0 : kz + 1;
        ky = kx == 2 ? 0 : kx + 1;
        // Keep the winding: swapping kx and ky when the dominant component is negative
        // keeps the sign convention of the edge functions independent of direction.
        if (r.dir[kz] < 0.0f) std::swap(kx, ky);
        sx = r.dir[kx] / r.dir[kz];
        sy = r.dir[ky] / r.dir[kz];
        sz = 1.0f / r.dir[kz];
    }
};

namespace detail {

// The end of the test in double, from the sheared float coordinates. Used where float
// loses the answer: an edge function that is exactly zero (the edge case of the paper),
// and results that underflow or overflow float (scenes scaled near the denormal range,
// where 1 / det overflows and t_scaled underflows to zero, which gave NaN or t = 0).
// The products of two floats are exact in double, so each edge function is rounded once
// and has the exact sign of the 2D determinant; a non-zero float edge function has that
// same sign (rounding is monotonic), so switching precision for one triangle never
// changes a sign its neighbour computed: the test stays watertight.
inline bool finish_in_double(float ax, float ay, float bx, float by, float cx, float cy, float az, float bz, float cz,
                             float tmin, float tmax, float& t_out, float& u_out, float& v_out) {
    const double e0 = double(cx) * double(by) - double(cy) * double(bx);
    const double e1 = double(ax) * double(cy) - double(ay) * double(cx);
    const double e2 = double(bx) * double(ay) - double(by) * double(ax);
    if ((e0 < 0 || e1 < 0 || e2 < 0) && (e0 > 0 || e1 > 0 || e2 > 0)) return false;
    const double det = e0 + e1 + e2;
    if (det == 0.0) return false;
    const double t = (e0 * double(az) + e1 * double(bz) + e2 * double(cz)) / det;
    if (!(t >= double(tmin) && t < double(tmax))) return false;
    t_out = float(t);
    u_out = float(e1 / det);
    v_out = float(e2 / det);
    return true;
}

}  // namespace detail

// Tests one triangle. On a hit with tmin <= t < tmax, writes t and barycentrics (u for p1,
// v for p2) and returns true. Degenerate triangles (zero determinant) never hit, and no
// path divides by zero or produces NaN from valid inputs (finite vertices below
// kMaxCoordinate, is_valid_ray rays).
inline bool intersect_triangle(const WatertightRay& r, const Vec3& p0, const Vec3& p1, const Vec3& p2, float tmin,
                               float tmax, float& t_out, float& u_out, float& v_out) {
    if (!r.valid) return false;
    // The vertices relative to the origin, permuted to (kx, ky, kz). Components are read
    // by index from memory: Vec3's operator[] with a run-time axis is a chain of selects,
    // which made up a third of this test's instructions. Same subtractions, same result.
    // The corners are taken by reference: by value, GCC copied each triangle to the stack
    // (12 moves per test in the kd-tree's leaf loop) to index it there.
    auto rel = [&r](const Vec3& p, int k) { return (&p.x)[k] - (&r.org.x)[k]; };
    const float a_x = rel(p0, r.kx), a_y = rel(p0, r.ky), a_z = rel(p0, r.kz);
    const float b_x = rel(p1, r.kx), b_y = rel(p1, r.ky), b_z = rel(p1, r.kz);
    const float c_x = rel(p2, r.kx), c_y = rel(p2, r.ky), c_z = rel(p2, r.kz);
    const float ax = a_x - r.sx * a_z, ay = a_y - r.sy * a_z;
    const float bx = b_x - r.sx * b_z, by = b_y - r.sy * b_z;
    const float cx = c_x - r.sx * c_z, cy = c_y - r.sy * c_z;
    const float az = r.sz * a_z, bz = r.sz * b_z, cz = r.sz * c_z;

    // Scaled barycentrics: 2D edge functions of the sheared triangle.
    const float e0 = cx * by - cy * bx;
    const float e1 = ax * cy - ay * cx;
    const float e2 = bx * ay - by * ax;
    // Outside: edge functions of both strict signs. Tested before the zero check below, which
    // gives the same answers: a non-zero float edge function has the exact sign (see
    // finish_in_double), so with two of opposite signs the double-precision end returns false
    // too. Most tests end here, and the three NaN-aware equality tests (13 instructions in
    // GCC's code) then run only for the triangles the ray is not certainly outside.
    // The six comparisons are combined with the non-short-circuit | and &: one branch per
    // test. Written with || and &&, GCC branched on each comparison in turn (3.3 branches
    // a test), and which edge function's sign decides is data-dependent (callgrind's branch
    // simulation: 0.76 mispredictions per test before, 0.30 after; bvh split=sah, bunny).
    // Timed (old and new binary interleaved, trace / Embree, three rounds): bunny
    // bvh sah 1.99 1.99 1.98 -> 1.84 1.78 1.73, kdtree 3.42 3.43 3.42 -> 3.17 3.10 3.09; igea
    // kdtree 3.64 3.59 3.75 -> 3.45 3.31 3.20; the conference within its noise.
    const bool some_negative = (e0 < 0.0f) | (e1 < 0.0f) | (e2 < 0.0f);
    const bool some_positive = (e0 > 0.0f) | (e1 > 0.0f) | (e2 > 0.0f);
    if (some_negative & some_positive) return false;
    // An edge function of exactly zero is where float rounding decides which neighbour
    // owns an edge: decide it in double, where both neighbours see the same sign.
    if (e0 == 0.0f || e1 == 0.0f || e2 == 0.0f)
        return detail::finish_in_double(ax, ay, bx, by, cx, cy, az, bz, cz, tmin, tmax, t_out, u_out, v_out);
    const float det = e0 + e1 + e2;
    const float t_scaled = e0 * az + e1 * bz + e2 * cz;
    // A denormal determinant (1 / det would overflow) or a t_scaled that underflowed or
    // overflowed: float cannot give t here, double can.
    if (!(std::fabs(det) >= std::numeric_limits<float>::min()) ||
        !(std::fabs(t_scaled) >= std::numeric_limits<float>::min() &&
          std::fabs(t_scaled) <= std::numeric_limits<float>::max()))
        return detail::finish_in_double(ax, ay, bx, by, cx, cy, az, bz, cz, tmin, tmax, t_out, u_out, v_out);

    // t = t_scaled / det must lie in [tmin, tmax); compare before dividing, flipping the
    // inequalities with the sign of det.
    if (det > 0.0f) {
        if (t_scaled < tmin * det || !(t_scaled < tmax * det)) return false;
    } else {
        if (t_scaled > tmin * det || !(t_scaled > tmax * det)) return false;
    }
    const float inv_det = 1.0f / det;
    t_out = t_scaled * inv_det;
    u_out = e1 * inv_det;
    v_out = e2 * inv_det;
    return true;
}

}  // namespace accelbench
