#include "accelbench/verify/error_metrics.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace accelbench {

int64_t ulp_distance(float a, float b) {
    // Maps the bit patterns to integers that are ordered like the floats (negative
    // floats count down from zero), so the difference counts the floats in between.
    auto key = [](float f) {
        int32_t i;
        std::memcpy(&i, &f, sizeof i);
        return i < 0 ? int64_t(INT32_MIN) - i : int64_t(i);
    };
    const int64_t d = key(a) - key(b);
    return d < 0 ? -d : d;
}

HitErrors compare_hits(std::span<const Hit> hits, std::span<const Hit> reference, int64_t tie_ulps) {
    if (hits.size() != reference.size())
        throw std::invalid_argument("compare_hits: " + std::to_string(hits.size()) + " hits against " +
                                    std::to_string(reference.size()) + " reference hits");
    HitErrors e;
    e.rays = hits.size();
    std::vector<int64_t> t_err;
    for (size_t i = 0; i < hits.size(); ++i) {
        const Hit& h = hits[i];
        const Hit& r = reference[i];
        if (std::isnan(h.t) || std::isnan(h.u) || std::isnan(h.v)) {
            ++e.nan_results;
            continue;
        }
        if (h.found() != r.found()) {
            ++(r.found() ? e.false_misses : e.false_hits);
            continue;
        }
        if (!h.found()) continue;
        const int64_t ulps = ulp_distance(h.t, r.t);
        if (h.prim != r.prim) {
            if (ulps > tie_ulps) {
                ++e.prim_mismatches;
                continue;
            }
            ++e.ties;
        }
        t_err.push_back(ulps);
    }
    e.t_compared = t_err.size();
    if (!t_err.empty()) {
        auto mid = t_err.begin() + (t_err.size() - 1) / 2;
        std::nth_element(t_err.begin(), mid, t_err.end());
        e.t_err_ulp_p50 = double(*mid);
        e.t_err_ulp_max = double(*std::max_element(t_err.begin(), t_err.end()));
    }
    return e;
}

HitErrors compare_occlusion(std::span<const uint8_t> occluded, std::span<const uint8_t> reference) {
    if (occluded.size() != reference.size())
        throw std::invalid_argument("compare_occlusion: " + std::to_string(occluded.size()) + " answers against " +
                                    std::to_string(reference.size()) + " reference answers");
    HitErrors e;
    e.rays = occluded.size();
    for (size_t i = 0; i < occluded.size(); ++i) {
        if ((occluded[i] != 0) == (reference[i] != 0)) continue;
        ++(reference[i] ? e.false_misses : e.false_hits);
    }
    return e;
}

ImageErrors compare_images(const Image& image, const Image& reference, std::span<const Hit> hits,
                           std::span<const Hit> reference_hits, int samples_per_pixel) {
    if (image.width != reference.width || image.height != reference.height || image.rgb.size() != reference.rgb.size())
        throw std::invalid_argument("compare_images: image sizes differ (" + std::to_string(image.width) + "x" +
                                    std::to_string(image.height) + " against " + std::to_string(reference.width) + "x" +
                                    std::to_string(reference.height) + ")");
    const size_t pixels = size_t(image.width) * size_t(image.height);
    if (samples_per_pixel < 1 || hits.size() != pixels * size_t(samples_per_pixel) ||
        reference_hits.size() != hits.size())
        throw std::invalid_argument("compare_images: expected " + std::to_string(samples_per_pixel) +
                                    " hits per pixel for " + std::to_string(pixels) + " pixels, got " +
                                    std::to_string(hits.size()) + " and " + std::to_string(reference_hits.size()));
    ImageErrors e;
    e.pixels = pixels;
    double sum = 0.0;
    for (size_t i = 0; i < image.rgb.size(); ++i) {
        const double d = (double(image.rgb[i]) - double(reference.rgb[i])) / 255.0;
        sum += d * d;
    }
    e.image_rmse = image.rgb.empty() ? 0.0 : std::sqrt(sum / double(image.rgb.size()));
    const size_t spp = size_t(samples_per_pixel);
    for (size_t p = 0; p < pixels; ++p) {
        for (size_t s = p * spp; s < (p + 1) * spp; ++s) {
            if (reference_hits[s].found() && !hits[s].found()) {
                ++e.hole_pixels;
                break;
            }
        }
    }
    return e;
}

}  // namespace accelbench
