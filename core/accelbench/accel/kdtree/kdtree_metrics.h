// The statistics of a built kd-tree, computed as every tree's (tree_tally.h).
#pragma once

#include "accelbench/accel/accelerator.h"
#include "accelbench/accel/kdtree/kdtree.h"

namespace accelbench {

// Statistics of a built kd-tree (tree_tally.h): nodes, leaves (empty ones included),
// max_depth (deepest leaf; root = 0), avg_leaf_size (primitive references per leaf),
// memory_bytes (nodes, the shared primitive-index array and the triangle copy; inline single
// primitives cost nothing extra) and sah_cost; extra: sah_cost_build (pbrt's model with THIS
// build's C_T and C_I and no empty bonus, what its SAH minimised), prim_refs (references over
// all leaves), empty_leaves, bad_refines, max_depth_limit (the max_depth applied).
BuildStats measure_kdtree(const KdTree& tree);

}  // namespace accelbench
