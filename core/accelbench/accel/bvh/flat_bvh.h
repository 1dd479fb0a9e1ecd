// The flattened binary BVH that the top-down BVH (bvh.h) and the LBVH (lbvh.h) both build
// and both traverse (bvh_traversal.h): the nodes (bvh_node.h) in one array in depth-first
// order, plus the leaves' primitives and their triangles in leaf order.
#pragma once

#include <cstdint>
#include <vector>

#include "accelbench/accel/bvh/bvh_node.h"
#include "accelbench/base/geometry.h"
#include "accelbench/base/tree_pieces.h"
#include "accelbench/scene/scene.h"

namespace accelbench {

// A leaf slot's triangle, copied out of the scene in leaf order: a leaf's triangles are
// then contiguous in memory, instead of three indirections (slot -> triangle -> three
// vertex indices -> three vertices scattered over the vertex array) per test.
struct LeafTriangle {
    Vec3 p0, p1, p2;
};

// A finished BVH. Builders fill `nodes` (depth-first, nodes[0] the root) and `prim_ids`
// (a leaf's slots are [first_prim, first_prim + prim_count)), then call finalize().
// An empty scene gives no nodes at all; traversal then answers "miss".
// Nodes are sized before a parallel build writes them (DefaultInitAllocator, base/default_init.h).
using BvhNodeArray = std::vector<BvhNode, DefaultInitAllocator<BvhNode>>;

struct FlatBvh {
    BvhNodeArray nodes;
    std::vector<uint32_t> prim_ids;  // slot -> triangle index in the scene
    // slot -> that triangle's vertices; released (empty) by a Bvh whose leaves are tested as
    // packets (bvh_packet_leaves.h), which hold the same vertices
    std::vector<LeafTriangle, DefaultInitAllocator<LeafTriangle>> triangles;
    uint32_t depth = 0;  // longest root-to-leaf path in edges (root alone: 0)

    // Copies each slot's triangle out of the scene and measures the depth (which sizes
    // the traversal stack, so a deep tree can never overflow it).
    void finalize(const Scene& scene);
    // The same for a builder that knows its tree's depth (the deepest leaf's): the depth
    // taken as given instead of walking the tree, the triangles copied on the build's threads
    // when `parallel`.
    void finalize(const Scene& scene, uint32_t tree_depth, bool parallel);

    bool empty() const { return nodes.empty(); }
};

// The nodes of node i's subtree are [i, subtree_end(i)): a depth-first subtree ends after
// its last second child's.
inline size_t subtree_end(const FlatBvh& bvh, size_t i) {
    while (!bvh.nodes[i].is_leaf()) i = bvh.nodes[i].second_child();
    return i + 1;
}

// A subtree of a binary BVH built by one task (base/tree_pieces.h): nodes only, as leaves
// index the slot arrays every task shares (each writes its own range of them).
struct NoLeafItems {};
using BvhPiece = TreePiece<BvhNode, NoLeafItems, BvhNodeArray>;

// Puts a tree built in pieces into `nodes` (depth-first, as one task would have written
// it); the root piece's node vector is left empty with its capacity, for the next build.
void assemble_bvh_pieces(BvhPiece& root, BvhNodeArray& nodes, bool parallel);

}  // namespace accelbench
