#include "accelbench/memory.h"

#include <gtest/gtest.h>

#include <vector>

using namespace accelbench;

TEST(Memory, PeakRssSeesAnAllocationAndResets) {
    const uint64_t before = peak_rss_bytes();
    ASSERT_GT(before, 0u);
    {
        std::vector<char> block(64 << 20, 1);  // touched, so resident
        EXPECT_GE(peak_rss_bytes(), before + (60u << 20));
        EXPECT_EQ(block[12345], 1);
    }
    if (reset_peak_rss()) {
        EXPECT_LT(peak_rss_bytes(), before + (60u << 20));
    }
}
