#include "accelbench/bvh_node.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace accelbench {

void FlatBvh::finalize(const Scene& scene) {
    triangles.resize(prim_ids.size());
    for (size_t slot = 0; slot < prim_ids.size(); ++slot) {
        const uint32_t p = prim_ids[slot];
        triangles[slot] = {scene.vertex(p, 0), scene.vertex(p, 1), scene.vertex(p, 2)};
    }
    // Depth-first order puts every child after its parent, so one forward pass can hand
    // each node's depth down to its two children.
    depth = 0;
    std::vector<uint32_t> node_depth(nodes.size(), 0);
    for (size_t i = 0; i < nodes.size(); ++i) {
        depth = std::max(depth, node_depth[i]);
        if (nodes[i].is_leaf()) continue;
        const uint32_t second = nodes[i].second_child();
        if (second <= i + 1 || second >= nodes.size())
            throw std::logic_error("FlatBvh: inner node " + std::to_string(i) + " has second child " +
                                   std::to_string(second) + ", not after its first child and inside the array");
        node_depth[i + 1] = node_depth[i] + 1;
        node_depth[second] = node_depth[i] + 1;
    }
}

}  // namespace accelbench
