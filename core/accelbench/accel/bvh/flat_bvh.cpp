#include "accelbench/accel/bvh/flat_bvh.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace accelbench {

void FlatBvh::finalize(const Scene& scene, uint32_t tree_depth, bool parallel) {
    triangles.resize(prim_ids.size());
    for_blocks(parallel, prim_ids.size(), 16384, [&](size_t, size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
            const uint32_t p = prim_ids[i];
            triangles[i] = {scene.vertex(p, 0), scene.vertex(p, 1), scene.vertex(p, 2)};
        }
    });
    depth = tree_depth;
}

void assemble_bvh_pieces(BvhPiece& root, BvhNodeArray& nodes, bool parallel) {
    nodes.clear();
    if (root.holes.empty()) {
        nodes.swap(root.nodes);
        return;
    }
    const uint64_t total = root.layout().first;
    nodes.resize(total);
    root.assemble(nodes.data(), nullptr, parallel, [](BvhNode& n, const BvhPiece::Map&, const BvhPiece::Map& refs) {
        if (!n.is_leaf()) n.index = uint32_t(refs.node(n.index));
    });
    root.nodes.clear();
}

void FlatBvh::finalize(const Scene& scene) {
    // Appended into reserved memory: resize() wrote every triangle as zeros first (36
    // bytes per slot, 12 MB for the conference) before the corners overwrote them.
    triangles.clear();
    triangles.reserve(prim_ids.size());
    for (const uint32_t p : prim_ids) triangles.push_back({scene.vertex(p, 0), scene.vertex(p, 1), scene.vertex(p, 2)});
    // In depth-first order a node follows either its parent (as first child) or, after a
    // leaf, the second child of the deepest ancestor not yet finished — the top of a
    // stack of pending second children. So one forward pass with that stack (at most
    // depth entries) knows every node's depth.
    depth = 0;
    struct Pending {
        uint32_t node, depth;
    };
    std::vector<Pending> pending;
    uint32_t d = 0;
    for (size_t i = 0; i < nodes.size(); ++i) {
        if (i > 0 && nodes[i - 1].is_leaf()) {
            if (pending.empty() || pending.back().node != i)
                throw std::logic_error("FlatBvh: node " + std::to_string(i) +
                                       " follows a leaf but is no pending second child (not depth-first)");
            d = pending.back().depth;
            pending.pop_back();
        } else if (i > 0) {
            ++d;  // first child of the inner node before it
        }
        depth = std::max(depth, d);
        if (nodes[i].is_leaf()) continue;
        const uint32_t second = nodes[i].second_child();
        if (second <= i + 1 || second >= nodes.size())
            throw std::logic_error("FlatBvh: inner node " + std::to_string(i) + " has second child " +
                                   std::to_string(second) + ", not after its first child and inside the array");
        pending.push_back({second, d + 1});
    }
    if (!pending.empty())
        throw std::logic_error("FlatBvh: second child " + std::to_string(pending.back().node) + " never reached");
}

}  // namespace accelbench
