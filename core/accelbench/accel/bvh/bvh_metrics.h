// Quality metrics of a finished FlatBvh, computed the same way for every binary BVH we
// build (top-down BVH and LBVH), so their BuildStats columns compare like with like.
//
// SAH cost of the finished tree (MacDonald & Booth 1990; the form used by Aila, Karras
// and Laine 2013, "On quality metrics of bounding volume hierarchies"):
//
//     cost = ( C_trav  * sum over inner nodes n of A(n)
//            + C_isect * sum over leaves l of A(l) * prims(l) ) / A(root)
//
// with A the surface area of the node's box, C_trav = 1 and C_isect = 1 (kSahCostTraversal,
// kSahCostIntersection, accelerator.h: every structure's sah_cost uses them), whatever
// constants the builder itself used. A(n)/A(root) is
// the probability that a random ray hitting the root also hits n, so the cost is the
// expected number of node visits plus triangle tests per such ray. A tree whose root box
// has zero area (no triangles, or all of them on one line or point) has no cost: it stays
// empty (missing), never 0.
#pragma once

#include <cstdint>
#include <optional>

#include "accelbench/accel/accelerator.h"
#include "accelbench/accel/bvh/flat_bvh.h"

namespace accelbench {

struct BvhMetrics {
    uint64_t nodes = 0;
    uint64_t leaves = 0;
    uint64_t max_depth = 0;     // edges on the longest root-to-leaf path (root alone: 0)
    uint64_t memory_bytes = 0;  // nodes + primitive ids + leaf triangle copies
    double avg_leaf_size = 0;   // primitives per leaf (0 without leaves)
    std::optional<double> sah_cost;
};

BvhMetrics measure_bvh(const FlatBvh& bvh);

// The BuildStats every binary BVH reports (extras left to the structure).
BuildStats bvh_build_stats(const FlatBvh& bvh);

}  // namespace accelbench
