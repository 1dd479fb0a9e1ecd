// How every tree's statistics are computed: the structure's measure_<tree>() walks its
// finished nodes and tallies each inner node and each leaf here; stats() turns the tally
// into the BuildStats columns, so that nodes, leaves, avg_leaf_size and sah_cost mean the
// same for every structure.
//
// SAH cost of the finished tree (MacDonald & Booth 1990; the form used by Aila, Karras and
// Laine 2013, "On quality metrics of bounding volume hierarchies"):
//
//     cost = ( C_trav  * sum over inner nodes n of A(n)
//            + C_isect * sum over leaves l of A(l) * prims(l) ) / A(root)
//
// with A the surface area of the node's box and, for the column, C_trav = C_isect = 1
// (kSahCostTraversal, kSahCostIntersection, accelerator.h), whatever constants the builder
// itself used. A(n)/A(root) is the probability that a random ray hitting the root also hits
// n, so the cost is the expected number of node visits plus triangle tests per such ray. A
// tree whose root box has no area (no triangles, or all of them on one line or point) has
// no cost: it stays empty (missing), never 0; so does the average leaf of a tree without
// leaves.
#pragma once

#include <cstdint>
#include <optional>

#include "accelbench/accel/accelerator.h"

namespace accelbench {

struct TreeTally {
    uint64_t nodes = 0;         // as the structure stores them (a wide BVH: its wide nodes)
    uint64_t max_depth = 0;     // edges on the longest path from the root to a leaf
    uint64_t memory_bytes = 0;  // what the finished tree holds
    double root_area = 0;
    uint64_t leaves = 0, prim_refs = 0;    // prim_refs: primitive references over all leaves
    double inner_area = 0, leaf_area = 0;  // sums in double (millions of terms); leaves' weighted by prims

    void inner(double area) { inner_area += area; }
    void leaf(double area, uint64_t prims) {
        ++leaves;
        prim_refs += prims;
        leaf_area += area * double(prims);
    }

    // The SAH cost with these constants; empty when the root box has no area.
    std::optional<double> sah_cost(double c_trav = kSahCostTraversal, double c_isect = kSahCostIntersection) const {
        if (!(root_area > 0)) return std::nullopt;
        return (c_trav * inner_area + c_isect * leaf_area) / root_area;
    }

    // The columns every tree reports (extras are the structure's own).
    BuildStats stats() const {
        BuildStats s;
        s.nodes = nodes;
        s.leaves = leaves;
        s.max_depth = max_depth;
        s.memory_bytes = memory_bytes;
        if (leaves) s.avg_leaf_size = double(prim_refs) / double(leaves);
        s.sah_cost = sah_cost();
        return s;
    }
};

}  // namespace accelbench
