// The node of the flattened binary BVH (flat_bvh.h) that the top-down BVH (bvh.h) and
// the LBVH (lbvh.h) both build and both traverse (bvh_traversal.h): 32 bytes, in one
// array in depth-first order.
//
// Why this layout (pbrt-v4's LinearBVHNode, madmann91/bvh v2's Node, and the compact
// kd-tree layout of the report's section 4): the first child of an inner node is the
// next node in the array, so a node stores only the index of its second child, and a
// descent to the first child reads the next 32 bytes (sequential, what the hardware
// prefetcher follows). The report's BVH (section 2.2.2) keeps separate heap nodes with
// child pointers; the tree is the same, only its storage differs. bvh v2's sibling-pair
// order (both children in one 64-byte line) and a 64-byte-aligned array were measured
// and did not pay on our rays (docs/decisions.md): the traversal is bound by
// instructions, not by cache misses.
#pragma once

#include <cstdint>

#include "accelbench/base/geometry.h"

namespace accelbench {

struct BvhNode {
    Bounds3 bounds;  // 24 bytes
    // Leaf: index of its first primitive slot (FlatBvh::prim_ids / triangles).
    // Inner node: index of its second child (the first child is this node's index + 1).
    uint32_t index = 0;
    // Bits 0..29: number of primitives of a leaf, 0 for an inner node.
    // Bits 30..31: the split axis of an inner node (0, 1, 2) — what the report's nodes
    // store as "the splitting axis" (section 2.2.2); kept for inspection and for
    // direction-sign ordering, free because the count never needs 32 bits.
    uint32_t count_axis = 0;

    static constexpr uint32_t kMaxLeafPrims = (1u << 30) - 1;

    bool is_leaf() const { return prim_count() != 0; }
    uint32_t prim_count() const { return count_axis & kMaxLeafPrims; }
    int axis() const { return int(count_axis >> 30); }
    uint32_t first_prim() const { return index; }
    uint32_t second_child() const { return index; }

    static BvhNode leaf(const Bounds3& b, uint32_t first, uint32_t count) { return {b, first, count}; }
    static BvhNode inner(const Bounds3& b, uint32_t second_child, int axis) {
        return {b, second_child, uint32_t(axis) << 30};
    }
};
static_assert(sizeof(BvhNode) == 32, "two nodes per 64-byte cache line");

}  // namespace accelbench
