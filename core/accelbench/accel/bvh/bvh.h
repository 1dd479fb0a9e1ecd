// The top-down BVH of the report (section 2): a binary tree of axis-aligned boxes built
// by "fit & split" from the root down (bvh_top_down.h), with the report's splitting
// criteria plus binned SAH, traversed by the shared BVH traversals (bvh_traversal.h).
//
// Parameters (report's Table 3 defaults: median split, maxPrims 1, depth 50):
//   split      median          object median of the centroids (report 2.2.1, its choice)
//              midpoint        centre of the node's centroid box — the report's "centroid
//                              method" (equation 1, Figures 7 and 8)
//              mean            mean of the centroids (report's "object mean")
//              spatial_median  where the summed triangle area of the two sides is equal
//                              (report's "spatial median", Figure 5c)
//              sah             binned SAH (Wald 2007, "On fast construction of SAH-based
//                              bounding volume hierarchies"), `bins` bins along the axis
//   axis       longest | round_robin     (report, Figure 6)
//   max_prims, max_depth, bins, traversal_cost, isect_cost, traversal.
#pragma once

#include <cstdint>

#include "accelbench/accel/accelerator.h"
#include "accelbench/accel/bvh/bvh_node.h"
#include "accelbench/accel/bvh/bvh_top_down.h"
#include "accelbench/accel/bvh/bvh_traversal.h"

namespace accelbench {

class Bvh final : public AcceleratorBase<Bvh> {
public:
    enum class Split { median, midpoint, mean, spatial_median, sah };

    static AcceleratorInfo info();
    explicit Bvh(const ParamSet& params);

    void build(const Scene& scene) override;
    BuildStats build_stats() const override;

    template <class C> void intersect(const Ray& ray, Hit& hit, C& counters) const;
    template <class C> bool occluded(const Ray& ray, C& counters) const;

    const FlatBvh& tree() const { return bvh_; }

private:
    Split split_;
    BvhTopDownSettings settings_;
    uint32_t bins_;
    float traversal_cost_, isect_cost_;
    BvhTraversal traversal_;
    FlatBvh bvh_;
    BvhTopDownCounts counts_;
};

}  // namespace accelbench
