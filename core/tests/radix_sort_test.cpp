#include "accelbench/base/radix_sort.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <span>
#include <vector>

#include "accelbench/base/parallel.h"

using namespace accelbench;

namespace {

// Items with values 0..n-1 in order (as the LBVH gives them), keys from `key_of`.
template <class Key, class F>
std::vector<KeyValue<Key>> make_items(size_t n, F key_of) {
    std::vector<KeyValue<Key>> v(n);
    for (size_t i = 0; i < n; ++i) v[i] = {Key(key_of(i)), uint32_t(i)};
    return v;
}

// Checks radix_sort against std::stable_sort: same keys AND same values in the same
// order, i.e. equal keys keep their input order.
template <class Key>
RadixSortStats expect_matches_stable_sort(std::vector<KeyValue<Key>> items, int key_bits, int digit_bits) {
    auto expected = items;
    std::stable_sort(expected.begin(), expected.end(), [](const auto& a, const auto& b) { return a.key < b.key; });
    std::vector<KeyValue<Key>> scratch;
    RadixSortStats stats = radix_sort(items, scratch, key_bits, digit_bits);
    EXPECT_EQ(items.size(), expected.size());
    for (size_t i = 0; i < items.size(); ++i) {
        if (items[i].key != expected[i].key || items[i].value != expected[i].value) {
            ADD_FAILURE() << "first difference at " << i << " (key_bits " << key_bits << ", digit_bits " << digit_bits
                          << "): got (" << items[i].key << ", " << items[i].value << "), want (" << expected[i].key
                          << ", " << expected[i].value << ")";
            break;
        }
    }
    return stats;
}

}  // namespace

TEST(RadixSort, Random30BitKeysMatchStableSort) {
    std::mt19937 rng(1);
    for (int digit_bits : {8, 11}) {
        for (size_t n : {0, 1, 2, 3, 17, 1000, 100000}) {
            auto items = make_items<uint32_t>(n, [&](size_t) { return uint32_t(rng()) & ((1u << 30) - 1); });
            RadixSortStats s = expect_matches_stable_sort(items, 30, digit_bits);
            EXPECT_EQ(s.passes, digit_bits == 8 ? 4 : 3);
        }
    }
}

TEST(RadixSort, Random63BitKeysMatchStableSort) {
    std::mt19937_64 rng(2);
    for (int digit_bits : {8, 11}) {
        auto items = make_items<uint64_t>(50000, [&](size_t) { return rng() >> 1; });
        RadixSortStats s = expect_matches_stable_sort(items, 63, digit_bits);
        EXPECT_EQ(s.passes, digit_bits == 8 ? 8 : 6);
        EXPECT_EQ(s.skipped_passes, 0);
    }
}

TEST(RadixSort, ManyDuplicatesStayInInputOrder) {
    // Few distinct keys: stability is what decides the order of the values.
    std::mt19937 rng(3);
    for (int digit_bits : {8, 11}) {
        auto items = make_items<uint64_t>(20000, [&](size_t) { return uint64_t(rng() % 5) << 40; });
        expect_matches_stable_sort(items, 63, digit_bits);
        auto small = make_items<uint32_t>(20000, [&](size_t) { return uint32_t(rng() % 3); });
        expect_matches_stable_sort(small, 30, digit_bits);
    }
}

TEST(RadixSort, AllEqualKeysSkipEveryPass) {
    for (int digit_bits : {8, 11}) {
        auto items = make_items<uint64_t>(1000, [](size_t) { return 0x5555'5555'5555'5555ull >> 1; });
        RadixSortStats s = expect_matches_stable_sort(items, 63, digit_bits);
        EXPECT_EQ(s.skipped_passes, s.passes);
    }
}

TEST(RadixSort, SkipsOnlyTheDigitsThatNeverVary) {
    // Keys that vary in their low 8 bits only: with 8-bit digits, 1 pass of 4 is needed.
    std::mt19937 rng(4);
    auto items = make_items<uint32_t>(5000, [&](size_t) { return 0x2A00'0000u | (rng() & 0xFF); });
    RadixSortStats s = expect_matches_stable_sort(items, 30, 8);
    EXPECT_EQ(s.passes, 4);
    EXPECT_EQ(s.skipped_passes, 3);
}

TEST(RadixSort, AlreadySortedAndReversedInput) {
    for (int digit_bits : {8, 11}) {
        expect_matches_stable_sort(make_items<uint64_t>(30000, [](size_t i) { return uint64_t(i) * 0x9E3779B9ull; }),
                                   63, digit_bits);
        expect_matches_stable_sort(make_items<uint32_t>(30000, [](size_t i) { return uint32_t(30000 - i); }), 30,
                                   digit_bits);
    }
}

TEST(RadixSort, OddDigitWidthsAndNarrowKeys) {
    std::mt19937 rng(6);
    for (int digit_bits : {1, 3, 7, 13, 16}) {
        auto items = make_items<uint32_t>(3000, [&](size_t) { return uint32_t(rng()) & ((1u << 12) - 1); });
        RadixSortStats s = expect_matches_stable_sort(items, 12, digit_bits);
        EXPECT_EQ(s.passes, (12 + digit_bits - 1) / digit_bits);
    }
    // 3-bit keys: the Morton codes of bits = 1.
    auto three = make_items<uint32_t>(100, [&](size_t) { return uint32_t(rng() & 7); });
    expect_matches_stable_sort(three, 3, 8);
}

TEST(RadixSort, GeneralFormSortsByTheKeyItIsGivenStably) {
    // Plain 64-bit items sorted by their upper 34 bits only (the kd-tree's root events):
    // the result must be std::stable_sort's by the same key, whether an odd number of
    // passes ran (the items are copied back from scratch) or an even one.
    std::mt19937_64 rng(7);
    const auto key_of = [](uint64_t x) { return x >> 30; };
    for (int digit_bits : {8, 11, 12, 16}) {
        for (size_t n : {0, 1, 2, 5000}) {
            std::vector<uint64_t> items(n);
            // Few distinct keys, so that stability decides much of the order.
            for (auto& x : items) x = ((rng() % 64) << 50) | (rng() & ((uint64_t(1) << 50) - 1));
            auto expected = items;
            std::stable_sort(expected.begin(), expected.end(),
                             [&](uint64_t a, uint64_t b) { return key_of(a) < key_of(b); });
            std::vector<uint64_t> scratch(n);
            const RadixSortStats s =
                radix_sort(std::span<uint64_t>(items), std::span<uint64_t>(scratch), 34, digit_bits, key_of);
            EXPECT_EQ(s.passes, (34 + digit_bits - 1) / digit_bits);
            EXPECT_EQ(items, expected) << "digit_bits " << digit_bits << ", n " << n;
        }
    }
}

TEST(RadixSort, UpperBitsOfIndexOrderedItemsGiveTheWholeKeysOrder) {
    // What the kd-tree relies on: items whose low bits are their index in the input
    // (ascending), sorted stably by the upper bits alone, come out in the order of the
    // whole 64-bit value.
    std::mt19937_64 rng(8);
    std::vector<uint64_t> items(20000);
    for (size_t i = 0; i < items.size(); ++i) items[i] = ((rng() % 300) << 30) | i;
    auto expected = items;
    std::sort(expected.begin(), expected.end());
    std::vector<uint64_t> scratch(items.size());
    radix_sort(std::span<uint64_t>(items), std::span<uint64_t>(scratch), 34, 12, [](uint64_t x) { return x >> 30; });
    EXPECT_EQ(items, expected);
}

// On several threads (blocks counted and scattered at once): the same items in the same
// order as the serial sort, with the same passes skipped, for inputs large enough to take the
// parallel passes, duplicates and constant digits included.
TEST(RadixSort, ParallelPassesGiveTheSerialResult) {
    std::mt19937_64 rng(17);
    const size_t n = 3 * radix_sort_detail::kParallelMin + 12345;
    for (int digit_bits : {8, 10, 11}) {
        // 30-bit keys, many repeats: low and top bits vary, the middle ones are 0 (a skipped pass).
        auto items = make_items<uint32_t>(n, [&](size_t) { return uint32_t(rng() % 256) | uint32_t(rng() % 4) << 28; });
        auto serial = items, parallel = items;
        std::vector<KeyValue<uint32_t>> scratch;
        const RadixSortStats s = radix_sort(serial, scratch, 30, digit_bits);
        for (int threads : {2, 7}) {
            auto p = parallel;
            std::vector<KeyValue<uint32_t>> scratch_p;
            RadixSortStats ps;
            BuildThreads(threads).run([&] { ps = radix_sort(p, scratch_p, 30, digit_bits, true); });
            EXPECT_EQ(ps.passes, s.passes) << digit_bits;
            EXPECT_EQ(ps.skipped_passes, s.skipped_passes) << digit_bits;
            ASSERT_EQ(p.size(), serial.size());
            for (size_t i = 0; i < n; ++i)
                ASSERT_TRUE(p[i].key == serial[i].key && p[i].value == serial[i].value)
                    << "threads " << threads << " digit_bits " << digit_bits << " item " << i;
        }
        EXPECT_GT(s.skipped_passes, 0) << digit_bits;  // the constant digit
    }
}

TEST(RadixSort, RejectsBadWidths) {
    std::vector<KeyValue<uint32_t>> items(3), scratch;
    EXPECT_THROW(radix_sort(items, scratch, 30, 0), std::invalid_argument);
    EXPECT_THROW(radix_sort(items, scratch, 30, 17), std::invalid_argument);
    EXPECT_THROW(radix_sort(items, scratch, 33, 8), std::invalid_argument);
    std::vector<uint64_t> plain(3), short_scratch(2);
    EXPECT_THROW(
        radix_sort(std::span<uint64_t>(plain), std::span<uint64_t>(short_scratch), 34, 8, [](uint64_t x) { return x; }),
        std::invalid_argument);
}
