#include "accelbench/base/image.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

// stb_image_write is a single-header library: its implementation is compiled here and only
// here. Its code trips warnings we treat as errors in our own code, so they are silenced
// for this include only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wall"
#pragma GCC diagnostic ignored "-Wextra"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO  // we write the file ourselves, to report why it failed
#include <stb_image_write.h>
#pragma GCC diagnostic pop

namespace accelbench {

void Image::set(int x, int y, Vec3 linear_rgb) {
    const size_t at = (size_t(y) * size_t(width) + size_t(x)) * 3;
    for (int c = 0; c < 3; ++c) {
        float v = linear_rgb[c];
        v = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;  // also maps NaN to 0
        rgb[at + c] = uint8_t(std::lround(255.0f * std::pow(v, 1.0f / 2.2f)));
    }
}

void Image::write_png(const std::string& path) const {
    if (width <= 0 || height <= 0 || rgb.size() != size_t(width) * size_t(height) * 3)
        throw std::runtime_error("cannot write PNG '" + path + "': the image is empty or its size is inconsistent");

    // Encode in memory first, so an encoder failure and a file-system failure give
    // different, precise messages.
    std::vector<uint8_t> png;
    auto append = [](void* context, void* data, int size) {
        auto* out = static_cast<std::vector<uint8_t>*>(context);
        const auto* bytes = static_cast<const uint8_t*>(data);
        out->insert(out->end(), bytes, bytes + size);
    };
    if (!stbi_write_png_to_func(append, &png, width, height, 3, rgb.data(), width * 3) || png.empty())
        throw std::runtime_error("cannot write PNG '" + path + "': encoding failed");

    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) throw std::runtime_error("cannot write PNG '" + path + "': " + std::strerror(errno));
    const size_t written = std::fwrite(png.data(), 1, png.size(), f);
    const int write_errno = errno;
    const bool closed = std::fclose(f) == 0;
    if (written != png.size())
        throw std::runtime_error("cannot write PNG '" + path + "': " + std::strerror(write_errno));
    if (!closed) throw std::runtime_error("cannot write PNG '" + path + "': " + std::strerror(errno));
}

}  // namespace accelbench
