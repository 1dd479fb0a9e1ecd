#include "accelbench/verify/error_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace accelbench;

TEST(UlpDistance, CountsFloatsBetweenAcrossZero) {
    EXPECT_EQ(ulp_distance(1.0f, 1.0f), 0);
    EXPECT_EQ(ulp_distance(1.0f, std::nextafter(1.0f, 2.0f)), 1);
    EXPECT_EQ(ulp_distance(0.0f, -0.0f), 0);
    const float tiny = std::numeric_limits<float>::denorm_min();
    EXPECT_EQ(ulp_distance(-tiny, tiny), 2);
    EXPECT_EQ(ulp_distance(2.0f, 1.0f), int64_t(1) << 23);
}

TEST(CompareHits, ClassifiesEveryKindOfError) {
    const float t = 10.0f;
    const float near_t = std::nextafter(t, 20.0f);
    const std::vector<Hit> reference = {
        {1, t, 0.1f, 0.1f},  // same prim, same t
        {1, t, 0.1f, 0.1f},  // same prim, t 1 ulp off
        {1, t, 0.1f, 0.1f},  // other prim, t 1 ulp off: tie
        {1, t, 0.1f, 0.1f},  // other prim, t far: mismatch
        {1, t, 0.1f, 0.1f},  // accel misses
        {},                  // accel hits
        {},                  // both miss
        {1, t, 0.1f, 0.1f},  // NaN t
    };
    const std::vector<Hit> hits = {
        {1, t, 0.1f, 0.1f},
        {1, near_t, 0.1f, 0.1f},
        {2, near_t, 0.1f, 0.1f},
        {2, 11.0f, 0.1f, 0.1f},
        {},
        {3, 5.0f, 0.2f, 0.2f},
        {},
        {1, std::numeric_limits<float>::quiet_NaN(), 0.1f, 0.1f},
    };
    const HitErrors e = compare_hits(hits, reference);
    EXPECT_EQ(e.rays, 8u);
    EXPECT_EQ(e.false_misses, 1u);
    EXPECT_EQ(e.false_hits, 1u);
    EXPECT_EQ(e.prim_mismatches, 1u);
    EXPECT_EQ(e.ties, 1u);
    EXPECT_EQ(e.nan_results, 1u);
    EXPECT_EQ(e.t_compared, 3u);  // rays 0, 1, 2: errors 0, 1, 1 ulps
    EXPECT_EQ(e.t_err_ulp_p50, 1.0);
    EXPECT_EQ(e.t_err_ulp_max, 1.0);
    EXPECT_THROW(compare_hits(hits, std::vector<Hit>(3)), std::invalid_argument);
    const HitErrors none = compare_hits({}, {});
    EXPECT_FALSE(none.t_err_ulp_p50.has_value());
}

TEST(CompareImages, RmseAndHolePixels) {
    Image a(2, 1), b(2, 1);
    a.rgb = {255, 255, 255, 0, 0, 0};
    b.rgb = {255, 255, 255, 255, 255, 255};
    // Two samples per pixel. Pixel 0: the reference hits one sample the accelerator
    // misses (a hole); pixel 1: both miss the first sample, both hit the second.
    const Hit hit{0, 1.0f, 0, 0}, miss{};
    const std::vector<Hit> accel = {hit, miss, miss, hit}, ref = {hit, hit, miss, hit};
    const ImageErrors e = compare_images(a, b, accel, ref, 2);
    EXPECT_EQ(e.pixels, 2u);
    EXPECT_EQ(e.hole_pixels, 1u);
    EXPECT_NEAR(e.image_rmse, std::sqrt(0.5), 1e-12);  // half the channels differ by 1
    EXPECT_THROW(compare_images(a, Image(1, 1), accel, ref, 2), std::invalid_argument);
    EXPECT_THROW(compare_images(a, b, accel, ref, 1), std::invalid_argument);
}
