// The top-down "fit & split" BVH builder of the report (section 2.2.1), with the question
// "where does this range split?" left to a split strategy. The top-down BVH (bvh.h) plugs
// in median / midpoint / mean / spatial median / binned SAH; any other criterion that
// partitions a range of primitive references (e.g. Morton-code bits, the report's view of
// the LBVH in section 3) can plug in the same way.
//
// The builder does what every criterion needs and must not get wrong:
//  - fit: each node's box is the union of its primitives' boxes, and the box of their
//    centroids (what the report's splitting works on, section 2.2.2) is computed in the
//    same pass;
//  - the split axis: the longest axis of the centroid box (report, Figure 6) or round
//    robin over x, y, z by depth;
//  - termination: a leaf when a range holds at most max_prims primitives, and a forced
//    (larger) leaf at max_depth (the report's depth parameter, Table 3), counted in
//    `forced_leaves`;
//  - degenerate ranges: when the strategy cannot separate a range (the centroids do not
//    spread along the axis, or one side would be empty) the range is split into two
//    equal halves along the longest centroid axis instead (nth_element), counted in
//    `degenerate_splits`. Every split therefore leaves both sides non-empty, so the build
//    always terminates, even on identical triangles;
//  - output: nodes in depth-first order (first child right after its parent), leaves'
//    primitives contiguous in leaf order, all in arrays allocated once — no per-node
//    allocation, no recursion (an explicit stack), O(n) work per node besides the
//    strategy's own.
#pragma once

#include <algorithm>
#include <concepts>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "accelbench/bvh_node.h"
#include "accelbench/scene.h"

namespace accelbench {

// What the builder moves around: a primitive's box and its index in the scene. The
// centroid is the box's centre (as Scene::centroids), recomputed when needed rather than
// stored, to keep the reference small.
struct BvhPrimRef {
    Bounds3 bounds;
    uint32_t id;

    float centroid(int axis) const { return 0.5f * (bounds.lower[axis] + bounds.upper[axis]); }
    Vec3 centroid() const { return bounds.center(); }
};

enum class BvhAxisRule { longest, round_robin };

struct BvhTopDownSettings {
    uint32_t max_prims = 1;   // a range of at most this many primitives becomes a leaf
    uint32_t max_depth = 50;  // nodes at this depth are leaves whatever their size (root: 0)
    BvhAxisRule axis = BvhAxisRule::longest;
};

struct BvhTopDownCounts {
    uint64_t degenerate_splits = 0;  // ranges the strategy could not separate (equal-count split instead)
    uint64_t forced_leaves = 0;      // leaves of more than max_prims primitives made at max_depth
};

// What a strategy is asked about one range.
struct BvhSplitRequest {
    Bounds3 bounds;           // of the primitives
    Bounds3 centroid_bounds;  // of their centroids; its extent along `axis` is > 0
    int axis;                 // chosen by the axis rule
    uint32_t depth;
    // True when the range is small enough (<= max_prims) to be a leaf: a strategy that
    // may stop early (SAH) answers "no split" when a leaf is cheaper.
    bool leaf_allowed;
};

// A strategy's answer: refs[0, mid) go to the first child, refs[mid, n) to the second,
// with 0 < mid < n; `axis` is stored in the node.
struct BvhSplit {
    size_t mid;
    int axis;
};

// A split strategy is a callable
//     std::optional<BvhSplit> operator()(std::span<BvhPrimRef> refs, const BvhSplitRequest&)
// that may reorder refs and answers where the range splits, or std::nullopt when it
// cannot separate the range (or, with leaf_allowed, prefers a leaf). A strategy with
//     static constexpr bool kMayStopEarly = true;
// is also asked about ranges of 2..max_prims primitives (SAH termination); others see
// only ranges above max_prims.
template <class Strategy>
concept BvhSplitStrategy = requires(Strategy s, std::span<BvhPrimRef> refs, const BvhSplitRequest& r) {
    { s(refs, r) } -> std::same_as<std::optional<BvhSplit>>;
};

namespace detail {

template <class S>
constexpr bool may_stop_early() {
    if constexpr (requires { S::kMayStopEarly; })
        return S::kMayStopEarly;
    else
        return false;
}

inline void fit(std::span<const BvhPrimRef> refs, Bounds3& bounds, Bounds3& centroid_bounds) {
    Bounds3 b, cb;
    for (const BvhPrimRef& r : refs) {
        b.extend(r.bounds);
        cb.extend(r.centroid());
    }
    bounds = b;
    centroid_bounds = cb;
}

// Splits a range into two halves by count along `axis` (the object median; also the
// fallback for ranges a strategy cannot separate).
inline BvhSplit split_equal_counts(std::span<BvhPrimRef> refs, int axis) {
    const size_t mid = refs.size() / 2;
    std::nth_element(refs.begin(), refs.begin() + mid, refs.end(),
                     [axis](const BvhPrimRef& a, const BvhPrimRef& b) { return a.centroid(axis) < b.centroid(axis); });
    return {mid, axis};
}

}  // namespace detail

// The references the builder starts from: one per scene triangle, in scene order.
inline std::vector<BvhPrimRef> bvh_prim_refs(const Scene& scene) {
    std::vector<BvhPrimRef> refs(scene.triangle_count());
    for (size_t i = 0; i < refs.size(); ++i) refs[i] = {scene.prim_bounds[i], uint32_t(i)};
    return refs;
}

template <BvhSplitStrategy Strategy>
FlatBvh build_bvh_top_down(const Scene& scene, const BvhTopDownSettings& settings, Strategy& strategy,
                           BvhTopDownCounts& counts) {
    constexpr bool kMayStopEarly = detail::may_stop_early<Strategy>();
    if (scene.triangle_count() > BvhNode::kMaxLeafPrims)
        throw std::runtime_error("bvh: scene '" + scene.name + "' has more triangles than a BVH node can count");
    FlatBvh bvh;
    counts = {};
    std::vector<BvhPrimRef> refs = bvh_prim_refs(scene);
    const uint32_t n = uint32_t(refs.size());
    if (n == 0) {
        bvh.finalize(scene);
        return bvh;
    }
    bvh.nodes.reserve(2 * size_t(n) - 1);  // a binary tree with non-empty leaves has at most 2n-1 nodes

    struct Range {
        uint32_t begin, end, depth;
        uint32_t parent;  // node whose second child this range becomes (kInvalidId: none)
        Bounds3 bounds, centroid_bounds;
    };
    std::vector<Range> pending;  // second children still to build; at most one per level
    Range range{0, n, 0, kInvalidId, {}, {}};
    detail::fit(refs, range.bounds, range.centroid_bounds);

    for (;;) {
        const uint32_t index = uint32_t(bvh.nodes.size());
        if (range.parent != kInvalidId) bvh.nodes[range.parent].index = index;
        const uint32_t count = range.end - range.begin;
        const std::span<BvhPrimRef> span(refs.data() + range.begin, count);

        // Leaf or split?
        std::optional<BvhSplit> split;
        const bool small = count <= settings.max_prims;
        if (count > 1 && range.depth < settings.max_depth && (!small || kMayStopEarly)) {
            const Vec3 extent = range.centroid_bounds.diagonal();
            const int axis = settings.axis == BvhAxisRule::longest ? max_axis(extent) : int(range.depth % 3);
            if (extent[axis] > 0.0f)
                split = strategy(span, {range.bounds, range.centroid_bounds, axis, range.depth, small});
            if (split && (split->mid == 0 || split->mid >= count))
                throw std::logic_error("bvh: split strategy returned an empty side");
            if (!split && !small) {
                ++counts.degenerate_splits;
                split = detail::split_equal_counts(span, max_axis(extent));
            }
        } else if (!small) {
            ++counts.forced_leaves;  // at max_depth with more than max_prims primitives
        }

        if (!split) {
            bvh.nodes.push_back(BvhNode::leaf(range.bounds, range.begin, count));
            if (pending.empty()) break;
            range = pending.back();
            pending.pop_back();
            continue;
        }
        bvh.nodes.push_back(BvhNode::inner(range.bounds, 0, split->axis));  // second child patched later
        const uint32_t mid = range.begin + uint32_t(split->mid);
        Range first{range.begin, mid, range.depth + 1, kInvalidId, {}, {}};
        Range second{mid, range.end, range.depth + 1, index, {}, {}};
        detail::fit(std::span<const BvhPrimRef>(refs.data() + first.begin, first.end - first.begin), first.bounds,
                    first.centroid_bounds);
        detail::fit(std::span<const BvhPrimRef>(refs.data() + second.begin, second.end - second.begin),
                    second.bounds, second.centroid_bounds);
        pending.push_back(second);
        range = first;
    }

    bvh.prim_ids.resize(n);
    for (uint32_t i = 0; i < n; ++i) bvh.prim_ids[i] = refs[i].id;
    bvh.finalize(scene);
    return bvh;
}

}  // namespace accelbench
