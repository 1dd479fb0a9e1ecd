#include "accelbench/accel/kdtree/kdtree_metrics.h"

#include <span>
#include <vector>

#include "accelbench/accel/tree_tally.h"

namespace accelbench {

uint64_t KdTree::memory_bytes() const {
    return nodes_.size() * sizeof(KdNode) + prim_indices_.size() * sizeof(uint32_t) +
        corners_.size() * sizeof(corners_[0]);
}

// Walks the tree with each node's box (tree_tally.h). sah_cost_build is the same sum with
// this build's C_T and C_I (pbrt's model without the empty bonus), what its SAH minimised.
BuildStats measure_kdtree(const KdTree& tree) {
    const std::span<const KdNode> nodes = tree.nodes();
    TreeTally t;
    t.nodes = nodes.size();
    t.max_depth = uint64_t(tree.deepest_leaf());
    t.memory_bytes = tree.memory_bytes();
    t.root_area = nodes.empty() ? 0.0 : double(tree.bounds().area());
    uint64_t empty_leaves = 0;
    struct Item {
        uint32_t node;
        Bounds3 box;
    };
    std::vector<Item> todo;
    if (!nodes.empty()) todo.push_back({0, tree.bounds()});
    while (!todo.empty()) {
        const Item it = todo.back();
        todo.pop_back();
        const KdNode& node = nodes[it.node];
        if (node.is_leaf()) {
            t.leaf(it.box.area(), node.prim_count());
            empty_leaves += node.prim_count() == 0;
        } else {
            t.inner(it.box.area());
            Bounds3 below = it.box, above = it.box;
            below.upper[node.axis()] = above.lower[node.axis()] = node.split();
            todo.push_back({node.above_child(), above});
            todo.push_back({it.node + 1, below});
        }
    }
    BuildStats s = t.stats();
    const KdTree::Config& config = tree.config();
    if (const auto build_cost = t.sah_cost(config.traversal_cost, config.isect_cost))
        s.extra["sah_cost_build"] = *build_cost;
    s.extra["prim_refs"] = double(t.prim_refs);
    s.extra["empty_leaves"] = double(empty_leaves);
    s.extra["bad_refines"] = double(tree.bad_refines());
    s.extra["max_depth_limit"] = double(tree.max_depth_used());
    return s;
}

BuildStats KdTree::build_stats() const { return measure_kdtree(*this); }

}  // namespace accelbench
