// How wrong an accelerator's answers are, measured against the reference structure
// (accel/baseline/reference.h): the error columns of every measured row.
//
// Inputs are what the renderer keeps with TraceRequest::keep_hits (TraceOutput::
// primary_hits): one Hit per primary ray, in the same order for the accelerator and for
// the reference (same rays). Nothing here traces rays; the harness traces both and calls
// these, outside the timed part.
#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include "accelbench/base/geometry.h"
#include "accelbench/base/image.h"

namespace accelbench {

// Distance in units in the last place between two floats: the number of representable
// floats between them (0 when equal; +0 and -0 are equal). Meaningless for NaN.
int64_t ulp_distance(float a, float b);

// Two different primitives hit at distances within this many float ulps are a tie (two
// triangles meeting where the ray hits them, or coplanar overlapping triangles), not an
// error: 64 ulps is a relative 64 * 2^-24 ~ 3.8e-6, well above the rounding of any float
// triangle test and well below any geometric feature the scenes resolve.
constexpr int64_t kTieUlps = 64;

struct HitErrors {
    uint64_t rays = 0;
    uint64_t false_misses = 0;     // the reference hits, the accelerator misses
    uint64_t false_hits = 0;       // the accelerator hits, the reference misses
    uint64_t prim_mismatches = 0;  // both hit, different primitives, t more than tie_ulps apart
    uint64_t ties = 0;             // both hit, different primitives, t within tie_ulps
    uint64_t nan_results = 0;      // the accelerator's t, u or v is NaN (hit or not)
    // Over rays where both hit the same primitive or tie (and the accelerator's t is not
    // NaN): ulp distance between the accelerator's t and the reference's t (rounded to
    // the nearest float). p50 is the lower median. Empty when no ray qualifies.
    uint64_t t_compared = 0;
    std::optional<double> t_err_ulp_p50, t_err_ulp_max;
};

// hits[i] and reference[i] answer the same ray. Throws std::invalid_argument if the
// sizes differ.
HitErrors compare_hits(std::span<const Hit> hits, std::span<const Hit> reference, int64_t tie_ulps = kTieUlps);

// Any-hit answers (shadow and ambient-occlusion rays, 1 = occluded) against the
// reference's: rays, false_misses (the reference finds an occluder, the accelerator does
// not) and false_hits; the other counts stay 0 and the t columns empty (an any-hit query
// returns no distance). Throws std::invalid_argument if the sizes differ.
HitErrors compare_occlusion(std::span<const uint8_t> occluded, std::span<const uint8_t> reference);

struct ImageErrors {
    uint64_t pixels = 0;
    // Root mean square difference over every pixel and channel, in [0, 1] (8-bit
    // values divided by 255).
    double image_rmse = 0.0;
    // Pixels showing background where the reference shows a surface: at least one of the
    // pixel's samples hits in the reference and misses in the accelerator.
    uint64_t hole_pixels = 0;
};

// Compares two renders of the same view. The hits are the renders' primary hits
// (samples_per_pixel consecutive hits per pixel, pixels row-major, as renderer.cpp keeps
// them). Throws std::invalid_argument when sizes do not match.
ImageErrors compare_images(const Image& image, const Image& reference, std::span<const Hit> hits,
                           std::span<const Hit> reference_hits, int samples_per_pixel);

}  // namespace accelbench
