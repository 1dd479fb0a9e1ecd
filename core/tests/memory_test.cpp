#include "accelbench/base/memory.h"

#include <gtest/gtest.h>

#include <vector>

using namespace accelbench;

TEST(Memory, PeakRssSeesAnAllocationAndResetsToTheCurrentSize) {
    const uint64_t before = peak_rss_bytes();
    ASSERT_GT(before, 0u);
    {
        std::vector<char> block(64 << 20, 1);  // touched, so resident
        EXPECT_GE(peak_rss_bytes(), before + (60u << 20));
        EXPECT_EQ(block[12345], 1);
    }
    // After a reset the peak is the resident size of the moment (under ASan the freed
    // block stays resident in its quarantine, so it need not drop below the old peak).
    if (reset_peak_rss()) {
        const uint64_t now = current_rss_bytes();
        EXPECT_LE(peak_rss_bytes(), now + (1u << 20));
        EXPECT_GE(peak_rss_bytes() + (1u << 20), now);
    }
}
