// The top-down BVH of the report (section 2): a binary tree of axis-aligned boxes built
// by "fit & split" from the root down (bvh_top_down.h), with the report's splitting
// criteria plus binned SAH, traversed by the shared BVH traversals (bvh_traversal.h).
//
// Parameters (report's Table 3 defaults: median split, maxPrims 1, depth 50):
//   split      median          object median of the centroids (report 2.2.1, its choice)
//              midpoint        centre of the node's centroid box — the report's "centroid
//                              method" (equation 1, Figures 7 and 8)
//              mean            mean of the centroids (report's "object mean")
//              spatial_median  where the summed triangle area of the two sides is equal
//                              (report's "spatial median", Figure 5c)
//              sah             binned SAH (Wald 2007, "On fast construction of SAH-based
//                              bounding volume hierarchies"), `bins` bins along the axis,
//                              or along all three in ranges of `all_axes_min` or more
//   axis       longest | round_robin     (report, Figure 6)
//   max_prims  the largest leaf. auto (the default): 1 for the report's splits (its Table 3),
//              8 for sah, which decides its own leaves below that bound: a range becomes a
//              leaf when its SAH cost is not above the best split's (as pbrt-v4 and bvh v2)
//   max_depth, bins, all_axes_min, traversal_cost, isect_cost, traversal,
//   leaf_test  scalar | packet | auto (packet where max_prims > 1): one triangle test at a
//              time or four per SSE test (bvh_packet_leaves.h), the same answers
//   reinsertion  passes of the reinsertion optimizer after the build (bvh_reinsertion.h;
//              0, the default, = off): a better tree for a longer build, same answers.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "accelbench/accel/accelerator.h"
#include "accelbench/accel/bvh/bvh_packet_leaves.h"
#include "accelbench/accel/bvh/bvh_reinsertion.h"
#include "accelbench/accel/bvh/bvh_top_down.h"
#include "accelbench/accel/bvh/bvh_traversal.h"
#include "accelbench/accel/bvh/flat_bvh.h"
#include "accelbench/base/parallel.h"

namespace accelbench {

class Bvh final : public AcceleratorBase<Bvh> {
public:
    enum class Split { median, midpoint, mean, spatial_median, sah };
    // The split names, in the enum's order: the declared choices and the parser both read
    // this list.
    static constexpr std::array<std::string_view, 5> kSplitNames = {"median", "midpoint", "mean", "spatial_median",
                                                                    "sah"};

    // The parameters: each member's initializer is its default; bvh.cpp's table declares them.
    struct Config {
        Split split = Split::median;              // where a node splits (report 2.2.1: median)
        BvhAxisRule axis = BvhAxisRule::longest;  // split axis (report, Figure 6)
        std::optional<uint32_t> max_prims;        // largest leaf; empty: default_max_prims(split)
        uint32_t max_depth = 50;                  // nodes at this depth are leaves (report Table 3)
        // SAH bins (split=sah). 32, as Embree's binned builder and wbvh's binary build use:
        // finer planes near the root, where the conference's large triangles make 16 bins
        // cut badly. Counted (accelbench render, primary / shadow box tests) 16 -> 32:
        // conference 19.55M / 12.86M -> 16.79M / 12.56M; bunny, igea, dragon within 1%.
        // Timed (accel_bench, the old and new binary interleaved, five rounds): conference
        // trace / Embree median 2.40 -> 2.15, build unchanged (0.64-0.69 both); the other
        // models within the noise. Only split=sah reads it: the report's splits build the
        // same trees.
        uint32_t bins = 32;
        // split=sah: ranges of at least this many triangles take the cheapest plane over all
        // three axes, smaller ones bin along `axis` only (0: none). Binning all three axes
        // costs about as much again per reference and level as the rest of the build, so it
        // is spent where a plane decides for the most rays: the top levels (1024: about 6 of
        // the bunny's 16, 10 of the dragon's 23). Measured (accelbench render
        // 320x240, primary + shadow; accel_bench, trace and build / Embree, two to six
        // rounds), all_axes_min 0 / 1 / 64 / 1024 / 4096: conference box tests 7.11M / 5.60M /
        // 5.88M / 5.91M / 5.96M, triangle tests 1.05M / 1.45M / 0.98M / 0.96M / 1.03M (at 1 the
        // small ranges' planes cost more triangle tests at an equal SAH cost: 39.42 against
        // 39.23 at 1024, 42.26 at 0); trace / Embree conference 1.90-1.97 at 0, 1.59-1.86 at
        // 1, 1.57-1.85 at 64, 1.57-1.84 at 1024; dragon 1.52-1.62 at 0, 1.44-1.65 at the
        // others; bunny 1.40-1.46 at 0, 1.34-1.47 at the others (igea level); build / Embree
        // bunny 0.57-0.58 at 0, 0.77-0.79 at 1, 0.52-0.53 at 1024, conference 0.56-0.59,
        // 0.90-0.98, 0.71-0.75 (the builds at 1 and 1024 with SahSplit's fused partition).
        uint32_t all_axes_min = 1024;
        // SAH cost of a node visit relative to isect_cost (split=sah): only the ratio counts,
        // and only in the leaf decision (a plane's cost adds the same C_trav A to every plane).
        // 4, the ratio that fits this traversal: a binary node visit (two box tests, the
        // near/far choice, the stack) costs far more than the fourth of a packet test that one
        // more triangle in a leaf adds. Measured (accel_bench, trace / Embree, two
        // or three rounds, packet leaves, bunny / igea / conference / dragon): 1 -> 1.56 /
        // 1.81-1.84 / 1.82-1.91 / 2.01-2.05, 3 -> 1.34-1.37 / 1.46-1.52 / 1.80-1.85 / 1.56-1.58,
        // 4 -> 1.32-1.51 / 1.41-1.46 / 1.83-2.00 / 1.47-1.50; 6 and max_prims 12-16 within the
        // same noise. Leaves at 4: 5.4 triangles on the bunny (1.8 at 1).
        float traversal_cost = 4.0f;
        float isect_cost = 1.0f;  // SAH cost of a triangle test (split=sah)
        BvhTraversal traversal = BvhTraversal::ordered;
        uint32_t reinsertion = 0;  // reinsertion passes after the build (0: off)
        int threads = 1;           // build threads (the tree is the same for every count)
        // How a leaf's triangles are tested: one at a time (scalar) or four per SSE test
        // (packet, bvh_packet_leaves.h); auto = packet where a leaf may hold more than one
        // triangle (split=sah's default max_prims 8), scalar for one-triangle leaves (the
        // report's splits; Tables 4 and 5's sah row at max_prims 1), where three lanes of
        // every packet would be empty. Measured there (trace / Embree, bvh
        // split=sah max_prims=1, two rounds): packet 2.07-2.08 / 2.75-2.77 / 2.76-2.87,
        // scalar 2.00-2.03 / 2.62-2.70 / 2.35-2.41 (bunny / conference / dragon).
        enum class LeafTest { automatic, scalar, packet };
        LeafTest leaf_test = LeafTest::automatic;
        bool packet_leaves() const {
            return leaf_test == LeafTest::packet || (leaf_test == LeafTest::automatic && leaf_limit() > 1);
        }

        static Config from(const ParamSet& params);
        // 1 for the report's splits, which always split down to one triangle; 8 for the
        // SAH, which stops earlier where a leaf is cheaper (pbrt-v4 and Embree use 4-8).
        static uint32_t default_max_prims(Split split) { return split == Split::sah ? 8 : 1; }
        uint32_t leaf_limit() const { return max_prims ? *max_prims : default_max_prims(split); }
    };

    static AcceleratorInfo info();
    explicit Bvh(const ParamSet& params);
    explicit Bvh(const Config& config);

    void build(const Scene& scene) override;
    BuildStats build_stats() const override;

    template <class C>
    void intersect(const Ray& ray, Hit& hit, C& counters) const;
    template <class C>
    bool occluded(const Ray& ray, C& counters) const;

    // The tree; with packet leaves its `triangles` are released (the packets hold them).
    const FlatBvh& tree() const { return bvh_; }
    const BvhPacketLeaves* packet_leaves() const { return config_.packet_leaves() ? &packets_ : nullptr; }

private:
    void build_on_threads(const Scene& scene);

    Config config_;
    BuildThreads threads_;
    FlatBvh bvh_;
    BvhPacketLeaves packets_;  // built when config_.packet_leaves()
    BvhTopDownCounts counts_;
    BvhReinsertionCounts reinsertion_counts_;
};

}  // namespace accelbench
