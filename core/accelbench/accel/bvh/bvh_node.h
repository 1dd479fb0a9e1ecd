// The flattened binary BVH that the top-down BVH (bvh.h) and the LBVH (lbvh.h) both build
// and both traverse (bvh_traversal.h): 32-byte nodes in one array in depth-first order,
// plus the leaves' primitives in leaf order.
//
// Why this layout (pbrt-v4's LinearBVHNode, madmann91/bvh v2's Node, and the compact
// kd-tree layout of the report's section 4): the first child of an inner node is the
// next node in the array, so a node stores only the index of its second child; two nodes
// fit in one 64-byte cache line and a descent to the first child touches memory that is
// usually already loaded. The report's BVH (section 2.2.2) keeps separate heap nodes with
// child pointers; the tree is the same, only its storage differs.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "accelbench/base/geometry.h"
#include "accelbench/scene/scene.h"

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

// A leaf slot's triangle, copied out of the scene in leaf order: a leaf's triangles are
// then contiguous in memory, instead of three indirections (slot -> triangle -> three
// vertex indices -> three vertices scattered over the vertex array) per test.
struct LeafTriangle {
    Vec3 p0, p1, p2;
};

// A finished BVH. Builders fill `nodes` (depth-first, nodes[0] the root) and `prim_ids`
// (a leaf's slots are [first_prim, first_prim + prim_count)), then call finalize().
// An empty scene gives no nodes at all; traversal then answers "miss".
struct FlatBvh {
    std::vector<BvhNode> nodes;
    std::vector<uint32_t> prim_ids;        // slot -> triangle index in the scene
    std::vector<LeafTriangle> triangles;   // slot -> that triangle's vertices
    uint32_t depth = 0;                    // longest root-to-leaf path in edges (root alone: 0)

    // Copies each slot's triangle out of the scene and measures the depth (which sizes
    // the traversal stack, so a deep tree can never overflow it).
    void finalize(const Scene& scene);

    bool empty() const { return nodes.empty(); }
};

}  // namespace accelbench
