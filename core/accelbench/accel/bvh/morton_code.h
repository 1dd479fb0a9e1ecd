// Morton codes (Z-order) of primitive centroids: the key the LBVH sorts by (report
// section 3.1, equation 3; Karras 2012, section 3).
//
// Each centroid is quantised to a 2^bits grid over the CENTROID bounds (not the scene
// bounds: the centroids are what the code must tell apart, and triangles sticking out of
// the centroid box would only waste grid cells), and the three grid coordinates are
// interleaved bit by bit, x in the lowest bit of each triple, then y, then z:
//     ... z1 y1 x1 z0 y0 x0
// the report's order. Sorting by that code orders the primitives along a Z-shaped
// space-filling curve, so primitives close in the sorted array are close in space, and
// every bit of the code is a splitting plane: bit 3k + a halves the cell on axis a.
//
// Widths: up to 10 bits per axis fit a 30-bit code in a uint32_t, up to 21 bits a 63-bit
// code in a uint64_t. Any bits in [1, 21] works; fewer bits only means coarser cells (and
// more primitives sharing a code).
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <type_traits>

#include "accelbench/base/geometry.h"

namespace accelbench {

// The widest grid coordinate a code type holds per axis: 3 * 10 = 30 <= 32 bits,
// 3 * 21 = 63 <= 64 bits.
template <class Code>
constexpr int kMortonMaxBits = sizeof(Code) == 4 ? 10 : 21;

constexpr int kMortonMinBits = 1;

// Spreads the low kMortonMaxBits<Code> bits of v so that bit i lands on bit 3i, with two
// zero bits between neighbours ("part by 2").
//
// Magic-number spreading instead of a loop over bits: each step moves the upper half of
// every group of bits up by a shift and masks away what would collide, halving the group
// size. For 10 bits in 32: groups of 16 -> 8 -> 4 -> 2 -> 1 bit, with the shifts 16, 8,
// 4, 2 and masks that keep the bits in their final triple-spaced slots. E.g. the first
// step, x | x << 16 masked with 0x030000FF, keeps bits 0-7 in place and moves bits 8-9 to
// 24-25. The 64-bit version does the same for 21 bits with one more step (shift 32).
// Five or six shift/or/and rounds per coordinate, no branches, no table.
template <class Code>
constexpr Code spread_bits(Code v) {
    static_assert(std::is_same_v<Code, uint32_t> || std::is_same_v<Code, uint64_t>);
    if constexpr (std::is_same_v<Code, uint32_t>) {
        v &= 0x000003FFu;                   // 10 bits: ---- ---- ---- ---- ---- --98 7654 3210
        v = (v | (v << 16)) & 0x030000FFu;  // ---- --98 ---- ---- ---- ---- 7654 3210
        v = (v | (v << 8)) & 0x0300F00Fu;   // ---- --98 ---- ---- 7654 ---- ---- 3210
        v = (v | (v << 4)) & 0x030C30C3u;   // ---- --98 ---- 76-- --54 ---- 32-- --10
        v = (v | (v << 2)) & 0x09249249u;   // ---- 9--8 --7- -6-- 5--4 --3- -2-- 1--0
    } else {
        v &= 0x1FFFFFull;
        v = (v | (v << 32)) & 0x001F00000000FFFFull;
        v = (v | (v << 16)) & 0x001F0000FF0000FFull;
        v = (v | (v << 8)) & 0x100F00F00F00F00Full;
        v = (v | (v << 4)) & 0x10C30C30C30C30C3ull;
        v = (v | (v << 2)) & 0x1249249249249249ull;
    }
    return v;
}

// Interleaves three grid coordinates (each below 2^kMortonMaxBits<Code>) in the report's
// order: x in bit 0 of each triple, y in bit 1, z in bit 2.
template <class Code>
constexpr Code morton_encode(uint32_t x, uint32_t y, uint32_t z) {
    return spread_bits<Code>(Code(x)) | (spread_bits<Code>(Code(y)) << 1) | (spread_bits<Code>(Code(z)) << 2);
}

// The axis a code bit splits: bit 3k + a belongs to axis a (0 = x, 1 = y, 2 = z).
constexpr int morton_bit_axis(int bit) { return bit % 3; }

// Maps points of a box to grid coordinates in [0, 2^bits - 1] per axis.
//
// The arithmetic is in double on purpose: the box extent of finite floats can overflow
// float (upper 3e38, lower -3e38), and 2^bits / extent for a tiny positive extent can
// overflow float to infinity, which would turn the 0 offset of the box's lower corner into
// 0 * inf = NaN. In double neither can happen for finite float input. An axis of zero
// extent (a flat scene, all centroids in one plane) gets scale 0, so every point
// quantises to cell 0 on that axis instead of dividing by zero.
class MortonQuantizer {
public:
    MortonQuantizer(const Bounds3& box, int bits) : last_cell_(double((uint32_t(1) << bits) - 1)) {
        for (int a = 0; a < 3; ++a) {
            lower_[a] = box.lower[a];
            const double extent = double(box.upper[a]) - double(box.lower[a]);
            // Cells of equal width extent / 2^bits; the upper face itself falls into cell
            // 2^bits and is clamped into the last cell below.
            scale_[a] = extent > 0 ? double(uint32_t(1) << bits) / extent : 0.0;
        }
    }

    uint32_t cell(float v, int axis) const {
        const double q = (double(v) - lower_[axis]) * scale_[axis];
        // Clamped without branches (min/max instructions; this runs three times per
        // primitive): the upper face lands on 2^bits and belongs to the last cell, and
        // points outside the box (not expected, but free to be safe against) go to the
        // border cells. (Argument order: std::max(0.0, q) would map a NaN to 0 too,
        // though none can arise from finite input; see the class comment.)
        return uint32_t(std::min(last_cell_, std::max(0.0, q)));
    }

    template <class Code>
    Code code(Vec3 p) const {
        return morton_encode<Code>(cell(p.x, 0), cell(p.y, 1), cell(p.z, 2));
    }

private:
    double lower_[3];
    double scale_[3];
    double last_cell_;
};

// Bounds of a set of points (the centroid bounds the codes are normalised to).
inline Bounds3 point_bounds(std::span<const Vec3> points) {
    Bounds3 b;
    for (const Vec3& p : points) b.extend(p);
    return b;
}

}  // namespace accelbench
