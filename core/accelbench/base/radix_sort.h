// Least-significant-digit radix sort of (key, value) pairs: the sort the LBVH build is
// made of (report section 3.1: "we can use a sorting algorithm as a Radix sort",
// Karras 2012). Keys are Morton codes, values primitive indices. The general form sorts
// any items by an unsigned key taken from each (the kd-tree sorts its root events, 64-bit
// integers, by their upper bits), which is why it lives in base/ for every structure.
//
// LSD radix sort makes one counting pass per digit, lowest digit first. Each pass is a
// stable counting sort, so after the pass on digit d the items are ordered by digits
// 0..d, and after the last pass by the whole key. Stability also means items with equal
// keys keep their input order; with values given in increasing order, equal Morton codes
// stay ordered by primitive index, which makes the LBVH deterministic.
//
// Two things keep it cheap:
//  - all digit histograms are counted in ONE read of the input before any scattering,
//    since a digit's histogram does not depend on the order of the items;
//  - a pass whose digit is the same for every item (one bucket holds all n) would only
//    copy the array, so it is skipped. Morton codes of a small grid (bits < 21 in a
//    64-bit key) or of a flat scene have whole digits that never vary.
//
// With `parallel` (inside a build's BuildThreads, base/parallel.h) each pass counts its digit
// per block of the input, and every block scatters its items at once from its own offsets:
// bucket by bucket, block by block, which is where the serial pass puts them. A stable sort
// has one result, so the items come out the same whatever the threads.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "accelbench/base/parallel.h"

namespace accelbench {

template <class Key>
struct KeyValue {
    Key key;
    uint32_t value;
};

struct RadixSortStats {
    int passes = 0;          // digits the key width needs
    int skipped_passes = 0;  // of those, digits every key shared
};

constexpr int kRadixMinDigitBits = 1;
constexpr int kRadixMaxDigitBits = 16;

namespace radix_sort_detail {

// Items per block of the parallel passes, and the fewest items sorted in parallel.
constexpr size_t kParallelBlock = size_t(1) << 16;
constexpr size_t kParallelMin = 2 * kParallelBlock;

// The passes of sort_passes below, each one's counting and scattering spread over blocks of
// the input (see the file comment). `stats` has its passes set.
template <class Item, class KeyOf>
void parallel_passes(Item*& in, Item*& out, size_t n, int digit_bits, KeyOf key_of, RadixSortStats& stats) {
    using Key = std::invoke_result_t<KeyOf, const Item&>;
    const size_t buckets = size_t(1) << digit_bits;
    const Key mask = Key(buckets - 1);
    const size_t blocks = block_count(n, kParallelBlock);
    // counts[block * buckets + bucket] of the pass being made, then that block's offsets.
    std::vector<uint32_t> counts(blocks * buckets);
    std::vector<uint32_t> total(buckets);
    for (int p = 0; p < stats.passes; ++p) {
        const int shift = p * digit_bits;
        std::fill(counts.begin(), counts.end(), 0u);
        for_blocks(true, n, kParallelBlock, [&](size_t b, size_t begin, size_t end) {
            uint32_t* c = counts.data() + b * buckets;
            for (size_t i = begin; i < end; ++i) ++c[size_t((key_of(in[i]) >> shift) & mask)];
        });
        std::fill(total.begin(), total.end(), 0u);
        for (size_t b = 0; b < blocks; ++b)
            for (size_t d = 0; d < buckets; ++d) total[d] += counts[b * buckets + d];
        if (std::find(total.begin(), total.end(), uint32_t(n)) != total.end()) {
            ++stats.skipped_passes;
            continue;
        }
        uint32_t sum = 0;
        for (size_t d = 0; d < buckets; ++d)
            for (size_t b = 0; b < blocks; ++b) {
                uint32_t& c = counts[b * buckets + d];
                const uint32_t here = c;
                c = sum;
                sum += here;
            }
        for_blocks(true, n, kParallelBlock, [&](size_t b, size_t begin, size_t end) {
            uint32_t* offsets = counts.data() + b * buckets;
            for (size_t i = begin; i < end; ++i) out[offsets[size_t((key_of(in[i]) >> shift) & mask)]++] = in[i];
        });
        std::swap(in, out);
    }
}

// The passes, ping-ponging between the buffers `in` and `out` of n items each; on return
// `in` points at the buffer holding the sorted items (the pointers are swapped per pass).
template <class Item, class KeyOf>
RadixSortStats sort_passes(Item*& in, Item*& out, size_t n, int key_bits, int digit_bits, KeyOf key_of, bool parallel) {
    using Key = std::invoke_result_t<KeyOf, const Item&>;
    static_assert(std::is_unsigned_v<Key>);
    if (digit_bits < kRadixMinDigitBits || digit_bits > kRadixMaxDigitBits)
        throw std::invalid_argument("radix_sort: digit_bits " + std::to_string(digit_bits) + " is outside [" +
                                    std::to_string(kRadixMinDigitBits) + ", " + std::to_string(kRadixMaxDigitBits) +
                                    "]");
    if (key_bits < 0 || key_bits > int(8 * sizeof(Key)))
        throw std::invalid_argument("radix_sort: key_bits " + std::to_string(key_bits) + " does not fit the key type");

    RadixSortStats stats;
    if (n > UINT32_MAX) throw std::invalid_argument("radix_sort: more than 2^32 - 1 items");
    stats.passes = (key_bits + digit_bits - 1) / digit_bits;
    if (n <= 1 || stats.passes == 0) return stats;
    // Wide digits would give every block a histogram too large to pay.
    if (parallel && n >= kParallelMin && digit_bits <= 12) {
        parallel_passes(in, out, n, digit_bits, key_of, stats);
        return stats;
    }

    const size_t buckets = size_t(1) << digit_bits;
    const Key mask = Key(buckets - 1);
    // Every pass's histogram, counted in one read (see the file comment). uint32_t counts
    // suffice: n < 2^32 is checked above.
    std::vector<uint32_t> counts(size_t(stats.passes) * buckets, 0);
    for (size_t i = 0; i < n; ++i) {
        Key k = key_of(in[i]);
        for (int p = 0; p < stats.passes; ++p, k >>= digit_bits) ++counts[size_t(p) * buckets + size_t(k & mask)];
    }

    for (int p = 0; p < stats.passes; ++p) {
        uint32_t* offsets = counts.data() + size_t(p) * buckets;
        const int shift = p * digit_bits;
        // One bucket holding every item: this digit is the same for all keys, and the
        // pass would reproduce its input.
        if (std::find(offsets, offsets + buckets, uint32_t(n)) != offsets + buckets) {
            ++stats.skipped_passes;
            continue;
        }
        // Counts -> start offsets (exclusive prefix sum), then scatter in input order,
        // which is what makes each pass stable.
        uint32_t sum = 0;
        for (size_t b = 0; b < buckets; ++b) {
            const uint32_t c = offsets[b];
            offsets[b] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; ++i) out[offsets[size_t((key_of(in[i]) >> shift) & mask)]++] = in[i];
        std::swap(in, out);
    }
    return stats;
}

}  // namespace radix_sort_detail

// Sorts `items` by key (stable), `digit_bits` per pass. Every key must be below
// 2^key_bits: only the passes that width needs are made (30-bit Morton codes: 4 passes of
// 8 bits or 3 of 11), which is the point of passing it. `scratch` is resized to items.size() and used as the other
// buffer of the ping-pong; passing the same scratch vector again avoids reallocating.
// On return the sorted items are in `items` (the vectors may have been swapped). `parallel`:
// on the build's threads (the same result).
template <class Key>
RadixSortStats radix_sort(std::vector<KeyValue<Key>>& items, std::vector<KeyValue<Key>>& scratch, int key_bits,
                          int digit_bits = 8, bool parallel = false) {
    scratch.resize(items.size());
    KeyValue<Key>* in = items.data();
    KeyValue<Key>* out = scratch.data();
    const RadixSortStats stats = radix_sort_detail::sort_passes(
        in, out, items.size(), key_bits, digit_bits, [](const KeyValue<Key>& item) { return item.key; }, parallel);
    if (in != items.data()) items.swap(scratch);
    return stats;
}

// The general form: sorts `items` stably by the unsigned key `key_of(item)`, which must
// be below 2^key_bits, using `scratch` (at least items.size() long) as the other buffer.
// The sorted items end in `items` (copied back once when an odd number of passes ran).
template <class Item, class KeyOf>
RadixSortStats radix_sort(std::span<Item> items, std::span<Item> scratch, int key_bits, int digit_bits, KeyOf key_of,
                          bool parallel = false) {
    if (scratch.size() < items.size()) throw std::invalid_argument("radix_sort: scratch is shorter than the items");
    Item* in = items.data();
    Item* out = scratch.data();
    const RadixSortStats stats =
        radix_sort_detail::sort_passes(in, out, items.size(), key_bits, digit_bits, key_of, parallel);
    if (in != items.data()) std::copy(in, in + items.size(), items.data());
    return stats;
}

}  // namespace accelbench
