// Cost images: per-pixel traversal work (node visits, triangle tests) as heatmaps, the
// picture that shows where a structure spends its time and why one beats another
// (cf. the "cost visualisations" of Aila & Laine 2009 and pbrt's statistics images).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "accelbench/base/counters.h"
#include "accelbench/base/image.h"

namespace accelbench {

// The inferno colour map (perceptually uniform, dark = cheap, bright = costly) as 8-bit
// sRGB, t clamped to [0, 1].
std::array<uint8_t, 3> inferno(double t);

// `values` (width*height, row-major) as a heatmap with 0 black-purple and `max` (and
// above) pale yellow, linear in between.
Image heatmap(const std::vector<double>& values, int width, int height, double max);

// Writes PREFIX-node_visits.png and PREFIX-prim_tests.png (each scaled to its own maximum)
// and PREFIX-cost.csv (x, y, node_visits, prim_tests per pixel, primary and shadow rays
// together), from which the analysis draws heatmaps on a scale shared by several
// structures. Returns the files written.
std::vector<std::string> write_cost_images(const std::vector<RayStats>& per_pixel, int width, int height,
                                           const std::string& prefix);

}  // namespace accelbench
