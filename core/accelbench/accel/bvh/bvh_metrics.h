// The statistics of a finished FlatBvh, computed the same way for every binary BVH we
// build (top-down BVH and LBVH) and, through TreeTally, as every other tree's.
#pragma once

#include "accelbench/accel/accelerator.h"
#include "accelbench/accel/bvh/flat_bvh.h"

namespace accelbench {

// nodes, leaves, max_depth (edges on the longest root-to-leaf path; root alone: 0),
// memory_bytes (nodes + primitive ids + leaf triangle copies), avg_leaf_size (primitives
// per leaf) and sah_cost (tree_tally.h); extras are left to the structure.
BuildStats measure_bvh(const FlatBvh& bvh);

}  // namespace accelbench
