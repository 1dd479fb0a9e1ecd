#include "accelbench/accel/bvh/bvh_metrics.h"

namespace accelbench {

BvhMetrics measure_bvh(const FlatBvh& bvh) {
    BvhMetrics m;
    m.nodes = bvh.nodes.size();
    m.max_depth = bvh.depth;
    m.memory_bytes = bvh.nodes.size() * sizeof(BvhNode) + bvh.prim_ids.size() * sizeof(uint32_t) +
        bvh.triangles.size() * sizeof(LeafTriangle);
    double inner_area = 0, leaf_area = 0;  // sums in double: millions of terms
    uint64_t prims = 0;
    for (const BvhNode& n : bvh.nodes) {
        if (n.is_leaf()) {
            ++m.leaves;
            prims += n.prim_count();
            leaf_area += double(n.bounds.area()) * n.prim_count();
        } else {
            inner_area += n.bounds.area();
        }
    }
    if (m.leaves) m.avg_leaf_size = double(prims) / double(m.leaves);
    const double root_area = bvh.empty() ? 0.0 : double(bvh.nodes[0].bounds.area());
    if (root_area > 0) m.sah_cost = (kSahCostTraversal * inner_area + kSahCostIntersection * leaf_area) / root_area;
    return m;
}

BuildStats bvh_build_stats(const FlatBvh& bvh) {
    const BvhMetrics m = measure_bvh(bvh);
    BuildStats s;
    s.nodes = m.nodes;
    s.leaves = m.leaves;
    s.max_depth = m.max_depth;
    s.memory_bytes = m.memory_bytes;
    if (m.leaves) s.avg_leaf_size = m.avg_leaf_size;
    s.sah_cost = m.sah_cost;
    return s;
}

}  // namespace accelbench
