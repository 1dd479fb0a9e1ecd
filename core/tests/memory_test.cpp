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

#if defined(__GLIBC__)
#include <malloc.h>

#include <cstdlib>

// Once a 1 MiB mapped block is freed, glibc's dynamic threshold would serve the next
// 256 KiB block from the heap; fixed, it is mapped fresh (one more mapped block).
TEST(Memory, FixedMallocThresholdsMapEveryLargeBlockFresh) {
    if (!fix_malloc_thresholds()) GTEST_SKIP() << "this allocator takes no thresholds (a sanitizer's)";
    void* volatile large = std::malloc(1 << 20);  // volatile: never elided
    ASSERT_NE(large, nullptr);
    std::free(large);
    const size_t mapped_before = mallinfo2().hblks;
    void* volatile medium = std::malloc(256 << 10);
    ASSERT_NE(medium, nullptr);
    EXPECT_EQ(mallinfo2().hblks, mapped_before + 1);
    std::free(medium);
}
#endif
