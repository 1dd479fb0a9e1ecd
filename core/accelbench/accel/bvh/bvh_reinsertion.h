// Post-build tree optimisation by reinsertion (Meister & Bittner 2018/2022, "Parallel
// reinsertion for bounding volume hierarchy optimization", Computer Graphics Forum 37(2),
// and its JCGT 11(4) revision; the form of madmann91/bvh v2's ReinsertionOptimizer).
//
// A reinsertion takes a node (with its subtree) out of the tree — its sibling takes its
// parent's place — and puts it back as the sibling of another node, the freed parent
// becoming their new parent. It changes the topology only: the same leaves with the same
// primitives, the same node count, every box refitted to what it bounds. So the tree
// answers every ray exactly as before (a box always encloses its subtree), only the work
// to get there changes.
//
// Each pass takes the nodes with the largest boxes (batch_ratio of all nodes, the ones
// whose position costs the most), finds for each the reinsertion that lowers the tree's
// summed inner-node surface area the most — a branch and bound search over the subtrees
// of its ancestors' siblings: the area removed from the old position minus the area added
// at the new one, pruned where even the node's own area can no longer be paid for — and
// applies the best ones that do not touch each other. The cost it lowers is the SAH's
// inner-node term (tree_tally.h); leaves keep their primitives, so the leaf term changes
// only through the leaves' positions.
#pragma once

#include <cstdint>

#include "accelbench/accel/bvh/flat_bvh.h"
#include "accelbench/scene/scene.h"

namespace accelbench {

struct BvhReinsertionConfig {
    uint32_t passes = 3;        // optimisation passes (bvh v2's max_iter_count: 3)
    float batch_ratio = 0.05f;  // fraction of the nodes tried per pass (bvh v2: 0.05)
};

struct BvhReinsertionCounts {
    uint64_t reinsertions = 0;  // moves applied over all passes
};

// Rewrites `bvh` (built over `scene`, finalized) into the optimised tree, again
// depth-first and finalized. A tree of fewer than three nodes is left as it is.
BvhReinsertionCounts optimize_bvh_by_reinsertion(FlatBvh& bvh, const Scene& scene, const BvhReinsertionConfig& config);

}  // namespace accelbench
