// Geometry shared by every structure: vectors, axis-aligned bounds, rays and hits.
//
// Everything here is single precision on purpose: that is what the report's ray tracer,
// pbrt and Embree trace with, and the error columns measure what float costs against the
// double-precision reference.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace accelbench {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

struct Vec3 {
    float x = 0, y = 0, z = 0;

    constexpr Vec3() = default;
    constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}

    constexpr float operator[](int axis) const { return axis == 0 ? x : (axis == 1 ? y : z); }
    constexpr float& operator[](int axis) { return axis == 0 ? x : (axis == 1 ? y : z); }

    constexpr Vec3 operator+(Vec3 o) const { return {x + o.x, y + o.y, z + o.z}; }
    constexpr Vec3 operator-(Vec3 o) const { return {x - o.x, y - o.y, z - o.z}; }
    constexpr Vec3 operator*(Vec3 o) const { return {x * o.x, y * o.y, z * o.z}; }
    constexpr Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3 operator/(float s) const { return {x / s, y / s, z / s}; }
    constexpr Vec3 operator-() const { return {-x, -y, -z}; }
    constexpr Vec3& operator+=(Vec3 o) {
        x += o.x;
        y += o.y;
        z += o.z;
        return *this;
    }
    constexpr bool operator==(const Vec3&) const = default;
};

constexpr Vec3 operator*(float s, Vec3 v) { return v * s; }
constexpr float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float length(Vec3 v) { return std::sqrt(dot(v, v)); }
inline Vec3 normalize(Vec3 v) { return v / length(v); }
constexpr Vec3 min(Vec3 a, Vec3 b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
constexpr Vec3 max(Vec3 a, Vec3 b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
constexpr int max_axis(Vec3 v) { return (v.x >= v.y && v.x >= v.z) ? 0 : (v.y >= v.z ? 1 : 2); }
inline bool is_finite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Reciprocal that never produces NaN: a zero component (of either sign) becomes an
// infinity of the same sign, so the slab test below sees +-inf and never 0 * inf.
inline float safe_inverse(float x) { return x != 0.0f ? 1.0f / x : std::copysign(kInfinity, x); }
inline Vec3 safe_inverse(Vec3 v) { return {safe_inverse(v.x), safe_inverse(v.y), safe_inverse(v.z)}; }

// Axis-aligned bounding box. The default box is empty (min = +inf, max = -inf), so that
// extending it with the first point or box gives exactly that point or box.
struct Bounds3 {
    Vec3 lower{kInfinity, kInfinity, kInfinity};
    Vec3 upper{-kInfinity, -kInfinity, -kInfinity};

    constexpr Bounds3() = default;
    constexpr Bounds3(Vec3 lo, Vec3 hi) : lower(lo), upper(hi) {}
    constexpr explicit Bounds3(Vec3 p) : lower(p), upper(p) {}

    constexpr void extend(Vec3 p) {
        lower = min(lower, p);
        upper = max(upper, p);
    }
    constexpr void extend(const Bounds3& b) {
        lower = min(lower, b.lower);
        upper = max(upper, b.upper);
    }
    constexpr bool empty() const { return lower.x > upper.x || lower.y > upper.y || lower.z > upper.z; }
    constexpr Vec3 diagonal() const { return upper - lower; }
    constexpr Vec3 center() const { return (lower + upper) * 0.5f; }
    constexpr int largest_axis() const { return max_axis(diagonal()); }
    // Surface area; 0 for an empty box so that empty children cost nothing in SAH sums.
    constexpr float area() const {
        if (empty()) return 0.0f;
        Vec3 d = diagonal();
        return 2.0f * (d.x * d.y + d.y * d.z + d.z * d.x);
    }
    constexpr bool operator==(const Bounds3&) const = default;
};

constexpr Bounds3 merge(Bounds3 a, const Bounds3& b) {
    a.extend(b);
    return a;
}

// The largest coordinate magnitude a scene or a ray may hold (exclusive): Embree's
// FLT_LARGE, 1.844e18 ~ sqrt(FLT_MAX) / 10. Products of two coordinate differences (the
// edge functions of the triangle test) stay finite below it. Embree silently ignores
// primitives with larger values (rtcCommitScene's documentation: "as no reasonable
// calculations can be performed with such values without causing overflows") and treats
// rays with larger components as invalid; Scene::finalize() rejects such faces and
// is_valid_ray() such rays, so every accelerator sees the same input.
constexpr float kMaxCoordinate = 1.844e18f;

// False for NaN, infinite and too large components.
inline bool within_coordinate_limit(Vec3 v) {
    return std::fabs(v.x) < kMaxCoordinate && std::fabs(v.y) < kMaxCoordinate && std::fabs(v.z) < kMaxCoordinate;
}

// A ray: origin, direction (not necessarily normalised) and the parametric interval
// [tmin, tmax] in which hits count.
struct Ray {
    Vec3 org;
    float tmin = 0.0f;
    Vec3 dir;
    float tmax = kInfinity;
};

// Whether a ray defines a line and an interval: origin and direction components finite
// and below kMaxCoordinate in magnitude, a non-zero direction, tmin and tmax not NaN
// (infinite bounds are fine). Every accelerator answers "miss" for any other ray.
inline bool is_valid_ray(const Ray& r) {
    return within_coordinate_limit(r.org) && within_coordinate_limit(r.dir) &&
        (r.dir.x != 0.0f || r.dir.y != 0.0f || r.dir.z != 0.0f) && !std::isnan(r.tmin) && !std::isnan(r.tmax);
}

constexpr uint32_t kInvalidId = 0xffffffffu;

// A closest hit: the primitive (triangle index in the scene), its distance along the
// ray and the barycentrics of the hit point (p = (1-u-v) p0 + u p1 + v p2).
struct Hit {
    uint32_t prim = kInvalidId;
    float t = kInfinity;
    float u = 0.0f;
    float v = 0.0f;

    constexpr bool found() const { return prim != kInvalidId; }
};

// What every box test needs from a ray, computed once per ray: the reciprocal direction
// (safe_inverse, so a zero component of either sign becomes +-inf) and, per axis, whether
// the ray travels toward the upper (0) or lower (1) plane first. Using the sign bit, not
// "dir < 0", sends a -0.0 component the same way as its -inf reciprocal.
struct RayPrecomp {
    Vec3 org;
    Vec3 inv_dir;
    int near_is_upper[3];
    // Where intersect_box reads axis a's near and far plane in a Bounds3 seen as six
    // floats (lower x, y, z, upper x, y, z): a + 3 * near_is_upper[a] and the other one.
    // An index load per plane instead of choosing between two Vec3 at every box test
    // (that choice was a third of the BVHs' box-test instructions on the bunny).
    uint32_t near_plane[3], far_plane[3];

    explicit RayPrecomp(const Ray& r) : org(r.org), inv_dir(safe_inverse(r.dir)) {
        for (int a = 0; a < 3; ++a) {
            near_is_upper[a] = std::signbit(inv_dir[a]) ? 1 : 0;
            near_plane[a] = uint32_t(a + 3 * near_is_upper[a]);
            far_plane[a] = uint32_t(a + 3 * (1 - near_is_upper[a]));
        }
    }
};

struct BoxHit {
    float tnear;
    float tfar;
    constexpr bool hit() const { return tnear <= tfar; }
};

// Each slab distance (plane - origin) * (1 / dir) carries three float roundings, so the
// near and far distances are each within gamma(3) = 3u / (1 - 3u) (u = 2^-24) of their
// true values (Ize 2013, "Robust BVH Ray Traversal -- revised", JCGT 2(2); pbrt-v3's
// Bounds3::IntersectP).
constexpr float kBoxSlack = 2.0f * (3.0f * 0x1p-24f / (1.0f - 3.0f * 0x1p-24f));

// The interval [slack_below(t), slack_above(t)] holds the true value of a distance t
// computed as (plane - origin) * (1 / dir), widened by kBoxSlack of its magnitude like
// intersect_box's far distance (Ize 2013). An infinite t (a zero direction component)
// stays itself, where t -+ kBoxSlack |t| would give NaN; NaN stays NaN.
// Branch-free: the slack is capped at the largest float, so an infinite t minus (plus) it
// stays infinite, and a finite t's slack (below 1e-6 |t|) is never capped; NaN stays NaN.
// The kd-tree computes both at every interior node it visits.
// Written `s < max ? s : max`, not std::min(s, max) (`max < s ? max : s`): the same value for
// every s but NaN, where it gives max instead of NaN, and t -+ max is NaN again for the NaN t
// that alone gives a NaN s; but it is one minss instead of a compare and a blend.
inline float slack_of(float t) {
    const float s = kBoxSlack * std::fabs(t);
    return s < std::numeric_limits<float>::max() ? s : std::numeric_limits<float>::max();
}
inline float slack_below(float t) { return t - slack_of(t); }
inline float slack_above(float t) { return t + slack_of(t); }

// Slab test (Williams et al. 2005, "An efficient and robust ray-box intersection"):
// the near and far planes per axis are picked by the direction's sign, so no min/max swap
// is needed. The only NaN possible is 0 * inf, when the origin lies exactly on a plane of
// an axis the ray does not move along; the comparisons are written "new value wins only if
// the test is true", so a NaN never replaces the interval and the ray counts as inside
// that slab — correct, since it runs along the box's face.
//
// Conservative: the far distance is enlarged by 2 gamma(3) of its magnitude (Ize 2013), so
// rounding never culls a box the ray enters, e.g. at the vertex or edge where a closed
// mesh's triangles meet on a box face — without it the BVHs leaked rays aimed exactly at
// vertices of a closed sphere (robustness case 1) that the watertight triangle test alone
// would have caught. The enlarged interval is returned (it only ever admits more boxes).
static_assert(sizeof(Bounds3) == 6 * sizeof(float) && offsetof(Bounds3, upper) == 3 * sizeof(float),
              "intersect_box reads a Bounds3 as six floats");
inline BoxHit intersect_box(const Bounds3& b, const RayPrecomp& r, float tmin, float tmax) {
    const float* planes = &b.lower.x;
    for (int a = 0; a < 3; ++a) {
        float tn = (planes[r.near_plane[a]] - r.org[a]) * r.inv_dir[a];
        float tf = (planes[r.far_plane[a]] - r.org[a]) * r.inv_dir[a];
        tmin = tn > tmin ? tn : tmin;
        tmax = tf < tmax ? tf : tmax;
    }
    return {tmin, tmax + kBoxSlack * std::fabs(tmax)};
}

}  // namespace accelbench
