#include "accelbench/accel/bvh/morton_code.h"

#include <gtest/gtest.h>

#include <random>

using namespace accelbench;

namespace {

// The obvious bit loop the magic-number spreading must equal.
template <class Code>
Code interleave_by_loop(uint32_t x, uint32_t y, uint32_t z, int bits) {
    Code c = 0;
    for (int i = 0; i < bits; ++i) {
        c |= Code((x >> i) & 1) << (3 * i);
        c |= Code((y >> i) & 1) << (3 * i + 1);
        c |= Code((z >> i) & 1) << (3 * i + 2);
    }
    return c;
}

}  // namespace

// Report section 3.1, equation 3 and its example: p_x = 1010, p_y = 0111, p_z = 1100
// interleave (z y x per bit, highest bit first) to 101 110 011 010.
TEST(MortonCode, ReportExample) {
    EXPECT_EQ(morton_encode<uint32_t>(0b1010, 0b0111, 0b1100), 0b101110011010u);
    EXPECT_EQ(morton_encode<uint64_t>(0b1010, 0b0111, 0b1100), 0b101110011010ull);
}

TEST(MortonCode, KnownValues) {
    EXPECT_EQ(morton_encode<uint32_t>(0, 0, 0), 0u);
    EXPECT_EQ(morton_encode<uint32_t>(1, 0, 0), 1u);
    EXPECT_EQ(morton_encode<uint32_t>(0, 1, 0), 2u);
    EXPECT_EQ(morton_encode<uint32_t>(0, 0, 1), 4u);
    EXPECT_EQ(morton_encode<uint32_t>(2, 0, 0), 8u);
    EXPECT_EQ(morton_encode<uint32_t>(1023, 1023, 1023), (1u << 30) - 1);
    EXPECT_EQ(morton_encode<uint32_t>(1u << 9, 0, 0), 1u << 27);
    EXPECT_EQ(morton_encode<uint32_t>(0, 0, 1u << 9), 1u << 29);
    EXPECT_EQ(morton_encode<uint64_t>((1u << 21) - 1, (1u << 21) - 1, (1u << 21) - 1), (1ull << 63) - 1);
    EXPECT_EQ(morton_encode<uint64_t>(0, 0, 1u << 20), 1ull << 62);
    EXPECT_EQ(morton_encode<uint64_t>(1u << 20, 0, 0), 1ull << 60);
    // Bits beyond the code's width are dropped, not smeared into other axes.
    EXPECT_EQ(spread_bits<uint32_t>(1u << 10), 0u);
    EXPECT_EQ(spread_bits<uint64_t>(1ull << 21), 0u);
}

TEST(MortonCode, SpreadingEqualsBitLoop) {
    std::mt19937 rng(5);
    for (int i = 0; i < 20000; ++i) {
        uint32_t x = rng(), y = rng(), z = rng();
        uint32_t x10 = x & 1023, y10 = y & 1023, z10 = z & 1023;
        ASSERT_EQ(morton_encode<uint32_t>(x10, y10, z10), interleave_by_loop<uint32_t>(x10, y10, z10, 10));
        uint32_t m21 = (1u << 21) - 1;
        ASSERT_EQ(morton_encode<uint64_t>(x & m21, y & m21, z & m21),
                  interleave_by_loop<uint64_t>(x & m21, y & m21, z & m21, 21));
    }
}

TEST(MortonCode, BitAxisFollowsInterleaveOrder) {
    EXPECT_EQ(morton_bit_axis(0), 0);
    EXPECT_EQ(morton_bit_axis(1), 1);
    EXPECT_EQ(morton_bit_axis(2), 2);
    EXPECT_EQ(morton_bit_axis(29), 2);
    EXPECT_EQ(morton_bit_axis(60), 0);
}

TEST(MortonQuantizer, CornersCentreAndClamp) {
    for (int bits : {1, 4, 10, 21}) {
        const uint32_t last = (1u << bits) - 1;
        MortonQuantizer q(Bounds3({-2, 0, 10}, {2, 8, 11}), bits);
        EXPECT_EQ(q.cell(-2, 0), 0u) << bits;
        EXPECT_EQ(q.cell(2, 0), last) << bits;  // the upper face clamps into the last cell
        EXPECT_EQ(q.cell(8, 1), last) << bits;
        EXPECT_EQ(q.cell(0, 0), 1u << (bits - 1)) << bits;  // centre starts the upper half
        EXPECT_EQ(q.cell(-100, 0), 0u) << bits;             // outside clamps
        EXPECT_EQ(q.cell(100, 2), last) << bits;
    }
    MortonQuantizer q10(Bounds3({0, 0, 0}, {1, 1, 1}), 10);
    EXPECT_EQ(q10.code<uint32_t>({0, 0, 0}), 0u);
    EXPECT_EQ(q10.code<uint32_t>({1, 1, 1}), (1u << 30) - 1);
    MortonQuantizer q21(Bounds3({0, 0, 0}, {1, 1, 1}), 21);
    EXPECT_EQ(q21.code<uint64_t>({1, 1, 1}), (1ull << 63) - 1);
    // Cells have equal width: 0.25 of the extent is exactly cell 256 of 1024.
    EXPECT_EQ(q10.cell(0.25f, 0), 256u);
    EXPECT_EQ(q10.cell(0.25f - 1e-6f, 0), 255u);
}

TEST(MortonQuantizer, MonotoneAlongEachAxis) {
    // With the other two coordinates fixed, a larger coordinate never gives a smaller
    // code: the Z curve visits cells of a row in order.
    const Bounds3 box({-1, -1, -1}, {3, 5, 7});
    for (int bits : {10, 21}) {
        MortonQuantizer q(box, bits);
        for (int axis = 0; axis < 3; ++axis) {
            Vec3 p{0.3f, -0.2f, 4.1f};
            uint64_t previous = 0;
            uint32_t previous_cell = 0;
            for (int i = 0; i <= 4000; ++i) {
                p[axis] = box.lower[axis] + (box.upper[axis] - box.lower[axis]) * float(i) / 4000.0f;
                uint64_t c = bits == 10 ? uint64_t(q.code<uint32_t>(p)) : q.code<uint64_t>(p);
                uint32_t cell = q.cell(p[axis], axis);
                if (i > 0) {
                    ASSERT_GE(c, previous) << "axis " << axis << " step " << i << " bits " << bits;
                    ASSERT_GE(cell, previous_cell);
                }
                previous = c;
                previous_cell = cell;
            }
            EXPECT_EQ(previous_cell, (1u << bits) - 1);
        }
    }
}

TEST(MortonQuantizer, ZeroExtentAxesQuantiseToZero) {
    // A flat scene: all centroids in the plane y = 3.
    MortonQuantizer flat(Bounds3({0, 3, 0}, {1, 3, 1}), 10);
    EXPECT_EQ(flat.cell(3, 1), 0u);
    EXPECT_EQ(flat.code<uint32_t>({1, 3, 1}), morton_encode<uint32_t>(1023, 0, 1023));
    // All centroids equal: every code is 0.
    MortonQuantizer point(Bounds3(Vec3{5, -7, 2}), 21);
    EXPECT_EQ(point.code<uint64_t>({5, -7, 2}), 0u);
}

TEST(MortonQuantizer, ExtremeExtentsStayInRange) {
    // An extent that overflows float (hi - lo = 6e38) and one that is denormal: neither may
    // produce NaN or a cell outside the grid.
    const float big = 3e38f;
    MortonQuantizer huge(Bounds3({-big, -big, -big}, {big, big, big}), 21);
    EXPECT_EQ(huge.cell(-big, 0), 0u);
    EXPECT_EQ(huge.cell(big, 0), (1u << 21) - 1);
    EXPECT_EQ(huge.cell(0, 0), 1u << 20);
    const float tiny = 1e-44f;  // denormal
    MortonQuantizer small(Bounds3({0, 0, 0}, {tiny, tiny, tiny}), 21);
    EXPECT_EQ(small.cell(0, 0), 0u);
    EXPECT_EQ(small.cell(tiny, 0), (1u << 21) - 1);
}

TEST(MortonQuantizer, PointBounds) {
    std::vector<Vec3> pts{{1, 2, 3}, {-1, 5, 0}, {0, 0, 9}};
    EXPECT_EQ(point_bounds(pts), Bounds3({-1, 0, 0}, {1, 5, 9}));
    EXPECT_TRUE(point_bounds({}).empty());
}
