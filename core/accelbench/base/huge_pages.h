// An allocator for the large arrays a traversal reads all over (tree nodes, leaf triangles):
// arrays of 2 MiB or more ask the kernel for transparent huge pages (2 MiB): a fresh mapping at a 2 MiB boundary, whole huge pages, madvise(MADV_HUGEPAGE)d, as
// Embree's allocator does for its BVH (alloc.cpp, os_madvise) — on a kernel whose THP mode is
// `madvise` (this machine's) only such memory gets huge pages. A traversal visits nodes and
// packets all over the tree; with 4 KiB pages the dragon's 60 MB of wbvh8 (14 MB nodes, 46 MB
// packets) spans 15,000 pages, far beyond the reach of the L2 TLB (3,072 entries, 12 MB, on
// this machine's Zen 4), so node and packet loads of its rays miss the TLB as well as the
// caches, while Embree's BVH lies in huge pages (AnonHugePages of the bench process: 59 MB).
// Measured (accel_bench, trace / Embree, interleaved, two A/B runs each), first with glibc's
// own switch (GLIBC_TUNABLES=glibc.malloc.hugetlb=1, the same madvise for every malloc'd
// mapping; load 9-14): dragon width 8 1.25x/1.22x -> 1.14x/1.14x, igea width 8 1.07x/1.03x ->
// 1.04x/1.05x; then with this allocator (load 3-10): dragon width 8 1.21x/1.22x -> 1.18x/1.15x,
// width 4 1.45x/1.43x -> 1.39x/1.38x; bunny, igea, conference within the noise (+-0.04). (The
// kernel granted 45-60 of the dragon's 60 MB as huge pages: what it has free at build time.)
// The callgrind cache simulation (which has no TLB) of the dragon's render at width 8 (its two
// passes, closest and any hit; 1 MiB last level, this machine's L2) puts the traversal's data
// misses on the packets' vertex rows (864K L1 / 456K L2 misses), then the nodes' planes (452K /
// 182K), child and count (44K / 19K) and the prim ids read on a hit (29K / 27K); the stack's
// are negligible (8K). The same tree, byte for byte; arrays under 2 MiB stay on ordinary pages
// (an array's last huge page is part-used: at most 2 MiB more than its capacity).
// Used by the wide BVH's tree only (for the binary BVH and the kd-tree: measured and not
// adopted, docs/decisions.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <vector>
#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "accelbench/base/default_init.h"

namespace accelbench {

// resize() and emplace_back() leave new elements unwritten (base/default_init.h): the tree's
// builders write every element, some of them on several threads.
template <class T>
struct HugePageAllocator : DefaultInitConstruct {
    using value_type = T;
    static constexpr size_t kHugePage = size_t(2) << 20;

    HugePageAllocator() = default;
    template <class U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

    static size_t rounded(size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }
    T* allocate(size_t n) {
        if (n > size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
        const size_t bytes = n * sizeof(T);
        if (bytes < kHugePage) return static_cast<T*>(::operator new(bytes, std::align_val_t(alignof(T))));
#if defined(__linux__)
        return static_cast<T*>(map_fresh(rounded(bytes)));
#else
        void* p = std::aligned_alloc(kHugePage, rounded(bytes));
        if (p == nullptr) throw std::bad_alloc();
        return static_cast<T*>(p);
#endif
    }
    void deallocate(T* p, size_t n) noexcept {
        if (n * sizeof(T) < kHugePage) ::operator delete(p, std::align_val_t(alignof(T)));
#if defined(__linux__)
        else munmap(p, rounded(n * sizeof(T)));
#else
        else std::free(p);
#endif
    }
#if defined(__linux__)
    // A fresh anonymous mapping of `bytes` (whole huge pages) at a 2 MiB boundary, madvised.
    // Mapped here rather than taken from malloc: malloc may hand out a free chunk of its heap
    // (in a forked measuring process, one its parent had already touched in 4 KiB pages, which
    // then stay 4 KiB pages and are copied on the first write), and whether it does depends on
    // what ran before (docs/decisions.md, "One combination, two configs").
    static void* map_fresh(size_t bytes) {
        void* raw = mmap(nullptr, bytes + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (raw == MAP_FAILED) throw std::bad_alloc();
        const auto start = reinterpret_cast<uintptr_t>(raw);
        const uintptr_t aligned = (start + kHugePage - 1) & ~uintptr_t(kHugePage - 1);
        if (aligned > start) munmap(raw, aligned - start);
        if (const size_t tail = start + kHugePage - aligned) munmap(reinterpret_cast<void*>(aligned + bytes), tail);
#if defined(MADV_HUGEPAGE)
        madvise(reinterpret_cast<void*>(aligned), bytes, MADV_HUGEPAGE);  // a hint: 4 KiB pages work as well
#endif
        return reinterpret_cast<void*>(aligned);
    }
#endif
    template <class U>
    bool operator==(const HugePageAllocator<U>&) const noexcept {
        return true;
    }
};
template <class T>
using HugePageArray = std::vector<T, HugePageAllocator<T>>;

}  // namespace accelbench
