// An 8-bit RGB image and PNG output.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "accelbench/base/geometry.h"

namespace accelbench {

struct Image {
    int width = 0;
    int height = 0;
    std::vector<uint8_t> rgb;  // row-major, 3 bytes per pixel, top row first

    Image() = default;
    Image(int w, int h) : width(w), height(h), rgb(size_t(w) * size_t(h) * 3, 0) {}

    // Stores a linear colour in [0, 1] (clamped) with sRGB-ish gamma 2.2.
    void set(int x, int y, Vec3 linear_rgb);
    // Throws std::runtime_error naming the path when writing fails.
    void write_png(const std::string& path) const;
};

}  // namespace accelbench
