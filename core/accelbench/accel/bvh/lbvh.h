// Linear BVH (report section 3; Lauterbach et al. 2009, Karras 2012, "Maximizing
// parallelism in the construction of BVHs, octrees, and k-d trees"): the BVH whose split
// criterion is the Morton code of the primitives' centroids.
//
// Building is sorting: every centroid gets a Morton code over the centroid bounds
// (morton_code.h), one radix sort orders the primitives along the Z curve (radix_sort.h),
// and the tree follows from the sorted codes alone. A node over a range of the sorted
// array splits where its highest differing code bit flips — the codes share every bit
// above it, so the first half of the range has that bit 0 and the second half 1, and a
// search finds the boundary (the report's Algorithm 2, Karras's findSplit). That bit is
// one plane of the Morton grid, so the split is a spatial-median split on axis bit % 3
// of the node's grid cell. No centroid is ever compared in floating point after the
// codes are made, and no bounds are needed to split.
//
// Two builds give that one tree (`build`), a third the median BVH's tree:
//   build=karras  Karras 2012: the split by binary search, each inner box the union of its
//                 children's, so the whole build after the sort is O(N).
//   build=report  the report's Algorithm 2 as written: each node's box fitted top-down
//                 from all its primitives (getGlobalAABB per node) and the split found by
//                 a linear scan for the first code whose leading differing bit has
//                 changed, O(N) per tree level. Min and max are exact, so a box fitted
//                 from the primitives equals the union of the children's boxes bit for
//                 bit, and both scans find the same boundary: the node arrays are
//                 byte-equal, and only the build time tells the builds apart.
//   build=median  the LBVH the report measured (section 5.2: "LBVH has to map the centre
//                 point of the 3D primitive to a Morton code, sort it by radix sort and
//                 then find a splitting point. These extra three stages add extra
//                 complexity"; section 3: it "acts as a splitting criterion of a BVH"):
//                 the Morton codes and the radix sort of the other builds, then the
//                 median BVH's top-down build (bvh_top_down.h, BvhMedianSplit), whose
//                 tree it is, node for node. The report's published code
//                 (github.com/Alhajras/Raytracer-Data-structures, accelerators.h,
//                 constructLBVHNew) builds its LBVH's subtrees with its BVH's median
//                 builder; this build measures what that costs: the BVH's build plus the
//                 two stages.
//
// Every stage runs on `threads` threads (Karras 2012 builds each in parallel): the codes,
// the radix sort and the gathering of the sorted boxes in blocks, the hierarchy as tasks —
// subtrees are independent, which is what the report parallelises too (section 3.2.1, its
// "conditional multithreading": a new thread only for subtrees above a threshold); here a
// second child above task_threshold primitives is handed out as a task, and the box fitting
// (Karras's bottom-up unions, or the report's top-down fits) happens inside each task. The
// tree does not depend on the thread count: each task builds its subtree into a piece of its
// own, and the pieces are assembled where a one-thread depth-first build puts them.
//
// The tree is the shared FlatBvh and is traversed by the shared traversals
// (bvh_traversal.h), exactly as the report reuses its BVH traversal (section 3.2).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "accelbench/accel/accelerator.h"
#include "accelbench/accel/bvh/bvh_traversal.h"
#include "accelbench/accel/bvh/flat_bvh.h"
#include "accelbench/base/parallel.h"
#include "accelbench/base/radix_sort.h"

namespace accelbench {

class Lbvh final : public AcceleratorBase<Lbvh> {
public:
    enum class Build { karras, report, median };
    // The build names, in the enum's order: the declared choices and the parser both read
    // this list.
    static constexpr std::array<std::string_view, 3> kBuildNames = {"karras", "report", "median"};

    // The parameters: each member's initializer is its default; lbvh.cpp's table declares them.
    struct Config {
        Build build = Build::karras;  // how the tree is built (karras and report: the same tree)
        // 10: on every model we have (bunny to the 871k dragon) 21 bits give the same tree
        // quality within 0.02% SAH, while 30-bit codes sort as 8-byte items in 3 passes
        // instead of 16-byte items in 6-7 (3-4x faster).
        int bits = 10;                  // Morton grid bits per axis
        uint32_t max_prims = 1;         // a range of at most this many primitives is a leaf (report: 1)
        uint32_t max_depth = 50;        // a node at this depth is a leaf (report: 50)
        int threads = 1;                // build threads (the parameter's 0, all cores, is stored as their number)
        uint32_t task_threshold = 100;  // a subtree goes to another thread only above this size (report: 100)
        // 10: a 30-bit code is exactly three digits, and three 1024-entry histograms
        // (12 KB) stay in L1 while counting. 8 needs a 4th pass.
        int sort_digit_bits = 10;  // radix sort digit width
        BvhTraversal traversal = BvhTraversal::ordered;

        static Config from(const ParamSet& params);
    };

    static AcceleratorInfo info();
    explicit Lbvh(const ParamSet& params);
    explicit Lbvh(const Config& config);

    void build(const Scene& scene) override;
    BuildStats build_stats() const override;

    template <class C>
    void intersect(const Ray& ray, Hit& hit, C& counters) const;
    template <class C>
    bool occluded(const Ray& ray, C& counters) const;

    // The finished tree (tests compare trees built with different thread counts).
    const FlatBvh& tree() const { return bvh_; }

    // What the build did beyond the tree itself (reported as BuildStats extras).
    struct Counts {
        uint64_t equal_code_splits = 0;    // ranges of one Morton code, split in the middle
        uint64_t forced_leaves = 0;        // leaves made at max_depth above max_prims
        uint64_t degenerate_splits = 0;    // build=median: ranges split in equal halves (bvh_top_down.h)
        uint64_t tasks = 0;                // subtrees handed to another thread
        uint64_t sort_passes = 0;          // radix passes the code width needs
        uint64_t sort_skipped_passes = 0;  // of those, skipped (digit constant)

        Counts& operator+=(const Counts& o);
    };

private:
    template <class Code>
    void build_with(const Scene& scene);

    // Bytes this object holds: the tree's and the build buffers' capacities.
    uint64_t reserved_bytes() const;

    Config config_;
    FlatBvh bvh_;
    Counts counts_;

    // Build buffers kept from one build to the next, like the tree's own arrays (a
    // rebuild reuses their capacity). Fresh memory costs a page fault per 4 KB touched:
    // on the bunny that was a quarter of the build time. Embree keeps its memory too.
    template <class Code>
    struct SortBuffers {
        std::vector<KeyValue<Code>> sorted, scratch;
    };
    SortBuffers<uint32_t> sort32_;
    SortBuffers<uint64_t> sort64_;
    std::vector<Bounds3> sorted_bounds_;
    BvhNodeArray spare_nodes_;  // several threads: the root piece's nodes (flat_bvh.h)
    BuildThreads threads_;
};

}  // namespace accelbench
