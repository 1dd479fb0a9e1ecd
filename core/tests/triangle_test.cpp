#include "accelbench/base/triangle.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace accelbench;

namespace {

bool hits(const Ray& r, Vec3 a, Vec3 b, Vec3 c, float* t_out = nullptr) {
    float t, u, v;
    bool h = intersect_triangle(WatertightRay(r), a, b, c, r.tmin, r.tmax, t, u, v);
    if (h) {
        EXPECT_FALSE(std::isnan(t));
        EXPECT_FALSE(std::isnan(u));
        EXPECT_FALSE(std::isnan(v));
        if (t_out) *t_out = t;
    }
    return h;
}

}  // namespace

TEST(Triangle, HitsInteriorWithCorrectTAndBarycentrics) {
    Ray r{{0.25f, 0.25f, -1.0f}, 0.0f, {0, 0, 1}, kInfinity};
    float t, u, v;
    ASSERT_TRUE(intersect_triangle(WatertightRay(r), {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0, kInfinity, t, u, v));
    EXPECT_FLOAT_EQ(t, 1.0f);
    EXPECT_FLOAT_EQ(u, 0.25f);
    EXPECT_FLOAT_EQ(v, 0.25f);
}

TEST(Triangle, MissesOutsideAndBehindAndBeyondTmax) {
    Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    EXPECT_FALSE(hits({{0.8f, 0.8f, -1}, 0, {0, 0, 1}, kInfinity}, a, b, c));     // outside the hypotenuse
    EXPECT_FALSE(hits({{0.2f, 0.2f, 1}, 0, {0, 0, 1}, kInfinity}, a, b, c));      // triangle behind origin
    EXPECT_FALSE(hits({{0.2f, 0.2f, -1}, 0, {0, 0, 1}, 0.5f}, a, b, c));          // beyond tmax
    EXPECT_FALSE(hits({{0.2f, 0.2f, -1}, 1.5f, {0, 0, 1}, kInfinity}, a, b, c));  // before tmin
}

TEST(Triangle, BothWindingsAndBothDirectionsHit) {
    Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    EXPECT_TRUE(hits({{0.2f, 0.2f, -1}, 0, {0, 0, 1}, kInfinity}, a, b, c));
    EXPECT_TRUE(hits({{0.2f, 0.2f, -1}, 0, {0, 0, 1}, kInfinity}, a, c, b));
    EXPECT_TRUE(hits({{0.2f, 0.2f, 1}, 0, {0, 0, -1}, kInfinity}, a, b, c));
}

// A ray through the edge shared by two triangles must hit at least one of them: this is
// what "watertight" means. Sweep many rays across the shared diagonal of a quad.
TEST(Triangle, SharedEdgeNeverLeaks) {
    Vec3 p00{-1.3f, -0.7f, 2.1f}, p10{1.1f, -0.9f, 2.3f}, p11{1.2f, 1.05f, 1.9f}, p01{-0.8f, 1.3f, 2.0f};
    int leaks = 0, both = 0;
    // Strictly inside the edge: at its end points the rounded direction may pass just
    // outside the quad's corner, where missing both is the right answer.
    for (int i = 1; i < 1000; ++i) {
        float s = i / 1000.0f;
        // Points on the shared edge p00-p11 (as exactly as float allows).
        Vec3 target = p00 + (p11 - p00) * s;
        Ray r{{0.1f, 0.05f, -3.0f}, 0, target - Vec3{0.1f, 0.05f, -3.0f}, kInfinity};
        bool h1 = hits(r, p00, p10, p11);
        bool h2 = hits(r, p00, p11, p01);
        if (!h1 && !h2) ++leaks;
        if (h1 && h2) ++both;
    }
    EXPECT_EQ(leaks, 0);
    (void)both;
}

// Axis-aligned rays at exactly representable points on an edge: the double fallback path.
TEST(Triangle, AxisAlignedRayOnSharedEdgeHitsOne) {
    Vec3 a{0, 0, 0}, b{2, 0, 0}, c{2, 2, 0}, d{0, 2, 0};
    for (float s : {0.0f, 0.25f, 0.5f, 1.0f, 1.5f, 2.0f}) {
        Ray r{{s, s, -1}, 0, {0, 0, 1}, kInfinity};
        EXPECT_TRUE(hits(r, a, b, c) || hits(r, a, c, d)) << "s=" << s;
    }
}

TEST(Triangle, DegenerateTrianglesNeverHitNeverNaN) {
    Ray r{{0.5f, 0.0f, -1}, 0, {0, 0, 1}, kInfinity};
    EXPECT_FALSE(hits(r, {0, 0, 0}, {1, 0, 0}, {2, 0, 0}));           // collinear, ray through the line
    EXPECT_FALSE(hits(r, {0.5f, 0, 0}, {0.5f, 0, 0}, {0.5f, 0, 0}));  // a point
    EXPECT_FALSE(hits(r, {0, 0, 0}, {1, 0, 0}, {1, 0, 0}));           // two coincident vertices
    Ray zero{{0, 0, 0}, 0, {0, 0, 0}, kInfinity};
    EXPECT_FALSE(hits(zero, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}));  // zero direction: invalid ray
    Ray nan_ray{{0, 0, 0}, 0, {NAN, 0, 1}, kInfinity};
    EXPECT_FALSE(hits(nan_ray, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}));
}

TEST(SlabTest, ZeroAndNegativeZeroDirectionsAreNaNFree) {
    Bounds3 box{{0, 0, 0}, {1, 1, 1}};
    // Origin exactly on the x = 0 face, moving along y: inside the slab, must hit.
    for (float zero : {0.0f, -0.0f}) {
        Ray r{{0, -1, 0.5f}, 0, {zero, 1, 0}, kInfinity};
        BoxHit h = intersect_box(box, RayPrecomp(r), r.tmin, r.tmax);
        EXPECT_TRUE(h.hit()) << "dir.x=" << zero;
        EXPECT_FLOAT_EQ(h.tnear, 1.0f);
        EXPECT_FLOAT_EQ(h.tfar, 2.0f);
        // Origin on the x = 1 face.
        Ray r2{{1, -1, 0.5f}, 0, {zero, 1, 0}, kInfinity};
        EXPECT_TRUE(intersect_box(box, RayPrecomp(r2), 0, kInfinity).hit()) << "dir.x=" << zero;
        // Origin outside the slab: must miss.
        Ray r3{{1.5f, -1, 0.5f}, 0, {zero, 1, 0}, kInfinity};
        EXPECT_FALSE(intersect_box(box, RayPrecomp(r3), 0, kInfinity).hit()) << "dir.x=" << zero;
    }
}

// Scaled toward the denormal range, the float edge functions (products of two
// coordinates) and t_scaled (of three) underflow: 1 / det overflowed to inf and t came
// out NaN (2^-64) or every ray missed (2^-90). The double finish must give the right t.
TEST(Triangle, TinyScalesGiveTheRightTNotNaN) {
    for (int exponent : {-40, -64, -90, -100}) {
        const float s = std::ldexp(1.0f, exponent);
        Ray r{{0.25f * s, 0.25f * s, -1.0f * s}, 0, {0, 0, 1}, kInfinity};
        float t, u, v;
        ASSERT_TRUE(intersect_triangle(WatertightRay(r), Vec3{0, 0, 0} * s, Vec3{1, 0, 0} * s, Vec3{0, 1, 0} * s, 0,
                                       kInfinity, t, u, v))
            << "scale 2^" << exponent;
        EXPECT_FLOAT_EQ(t, s) << "scale 2^" << exponent;
        EXPECT_FLOAT_EQ(u, 0.25f);
        EXPECT_FLOAT_EQ(v, 0.25f);
    }
}

TEST(Triangle, RaysWithoutAnIntervalOrBeyondTheCoordinateLimitMiss) {
    Vec3 a{0, 0, 1}, b{1, 0, 1}, c{0, 1, 1};
    EXPECT_FALSE(hits({{0.2f, 0.2f, 0}, NAN, {0, 0, 1}, kInfinity}, a, b, c));
    EXPECT_FALSE(hits({{0.2f, 0.2f, 0}, 0, {0, 0, 1}, NAN}, a, b, c));
    EXPECT_FALSE(hits({{0.2f, 0.2f, 0}, 0, {0, 0, 2e18f}, kInfinity}, a, b, c));
    EXPECT_TRUE(hits({{0.2f, 0.2f, 0}, 0, {0, 0, 1e18f}, kInfinity}, a, b, c));
}

// Rays aimed exactly at box corners and edge points from random origins: whenever the
// interval computed in double is clearly non-empty, the float slab test must hit too
// (Ize 2013's enlargement; without it about 1% of these rays were culled).
TEST(SlabTest, ConservativeAtCornersAndEdges) {
    uint64_t s = 12345;
    auto next = [&s] {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        return float(s >> 40) / float(1 << 24);
    };
    int clear_hits = 0, culled = 0;
    for (int i = 0; i < 20000; ++i) {
        Vec3 lo{next(), next(), next()}, hi = lo + Vec3{next(), next(), next()};
        const Bounds3 box{lo, hi};
        Vec3 target{next() < 0.5f ? lo.x : hi.x, next() < 0.5f ? lo.y : hi.y,
                    i % 2 ? lo.z + (hi.z - lo.z) * next() : hi.z};
        Vec3 org = Vec3{next(), next(), next()} * 8.0f - Vec3{4, 4, 4};
        Ray r{org, 0, target - org, kInfinity};
        double tn = 0, tf = INFINITY;
        for (int a = 0; a < 3; ++a) {
            if (r.dir[a] == 0) continue;
            double t0 = (double(lo[a]) - org[a]) / r.dir[a], t1 = (double(hi[a]) - org[a]) / r.dir[a];
            tn = std::max(tn, std::min(t0, t1));
            tf = std::min(tf, std::max(t0, t1));
        }
        if (!(tn < tf * (1 - 1e-12))) continue;  // empty or too close to call in double
        ++clear_hits;
        culled += !intersect_box(box, RayPrecomp(r), r.tmin, r.tmax).hit();
    }
    EXPECT_GT(clear_hits, 5000);
    EXPECT_EQ(culled, 0) << "of " << clear_hits;
}
