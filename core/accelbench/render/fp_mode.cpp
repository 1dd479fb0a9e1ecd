#include "accelbench/render/fp_mode.h"

#include <xmmintrin.h>

#include <array>

namespace accelbench {

namespace {
constexpr std::array<std::string_view, 2> kNames = {"ieee", "ftz_daz"};
// MXCSR bit 15 (FTZ) and bit 6 (DAZ); Intel SDM vol. 1, 10.2.3.
constexpr uint32_t kFtzDaz = 0x8040u;
}  // namespace

std::span<const std::string_view> fp_mode_names() { return kNames; }

std::string_view fp_mode_name(FpMode mode) { return kNames[size_t(mode)]; }

std::optional<FpMode> parse_fp_mode(std::string_view name) {
    for (size_t i = 0; i < kNames.size(); ++i)
        if (kNames[i] == name) return FpMode(i);
    return std::nullopt;
}

std::optional<FpMode> current_fp_mode() {
    const uint32_t bits = _mm_getcsr() & kFtzDaz;
    if (bits == kFtzDaz) return FpMode::FtzDaz;
    if (bits == 0) return FpMode::Ieee;
    return std::nullopt;
}

ScopedFpMode::ScopedFpMode(FpMode mode) : saved_(_mm_getcsr()) {
    _mm_setcsr(mode == FpMode::FtzDaz ? saved_ | kFtzDaz : saved_ & ~kFtzDaz);
}

ScopedFpMode::~ScopedFpMode() { _mm_setcsr(saved_); }

}  // namespace accelbench
