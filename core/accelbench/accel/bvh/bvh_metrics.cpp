#include "accelbench/accel/bvh/bvh_metrics.h"

#include "accelbench/accel/tree_tally.h"

namespace accelbench {

BuildStats measure_bvh(const FlatBvh& bvh) {
    TreeTally t;
    t.nodes = bvh.nodes.size();
    t.max_depth = bvh.depth;
    t.memory_bytes = bvh.nodes.size() * sizeof(BvhNode) + bvh.prim_ids.size() * sizeof(uint32_t) +
        bvh.triangles.size() * sizeof(LeafTriangle);
    t.root_area = bvh.empty() ? 0.0 : double(bvh.nodes[0].bounds.area());
    for (const BvhNode& n : bvh.nodes) {
        if (n.is_leaf()) t.leaf(n.bounds.area(), n.prim_count());
        else t.inner(n.bounds.area());
    }
    return t.stats();
}

}  // namespace accelbench
