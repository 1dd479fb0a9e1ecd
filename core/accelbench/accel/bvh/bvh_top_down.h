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
//    equal halves along the longest centroid axis instead (split_equal_counts), counted
//    in `degenerate_splits`. Every split therefore leaves both sides non-empty, so the build
//    always terminates, even on identical triangles;
//  - output: nodes in depth-first order (first child right after its parent), leaves'
//    primitives contiguous in leaf order, all in arrays allocated once — no per-node
//    allocation, no recursion (an explicit stack), O(n) work per node besides the
//    strategy's own (so O(n log n) for balanced trees).
#pragma once

#include <algorithm>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "accelbench/accel/bvh/flat_bvh.h"
#include "accelbench/scene/scene.h"

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
static_assert(sizeof(BvhPrimRef) == 28 && offsetof(BvhPrimRef, bounds) == 0);

// Box union over many references, the inner loop of every build pass, in 4-wide vectors
// (GCC/Clang vector extensions, so SSE/NEON without intrinsics): one min and one max
// instruction per reference instead of six scalar ones. A reference is read as two
// 16-byte loads, lower.xyz + upper.x and upper.xyz + id, both inside the 28-byte
// reference; the fourth lanes carry no meaning and are never read back.
class BvhBoxAccumulator {
public:
    using F4 = float __attribute__((vector_size(16)));

    void extend(const BvhPrimRef& r) {
        const F4 l = load(reinterpret_cast<const unsigned char*>(&r));
        const F4 h = load(reinterpret_cast<const unsigned char*>(&r) + sizeof(Vec3));
        lo_ = l < lo_ ? l : lo_;
        hi_ = h > hi_ ? h : hi_;
    }
    // Extends this box by r's box and `centroids` by r's centroid (the same arithmetic as
    // BvhPrimRef::centroid, so both agree bit for bit).
    void extend(const BvhPrimRef& r, BvhBoxAccumulator& centroids) {
        const F4 l = load(reinterpret_cast<const unsigned char*>(&r));
        const F4 h = load(reinterpret_cast<const unsigned char*>(&r) + sizeof(Vec3));
        lo_ = l < lo_ ? l : lo_;
        hi_ = h > hi_ ? h : hi_;
        const F4 c = 0.5f * (l + h);
        centroids.lo_ = c < centroids.lo_ ? c : centroids.lo_;
        centroids.hi_ = c > centroids.hi_ ? c : centroids.hi_;
    }
    void extend(const BvhBoxAccumulator& o) {
        lo_ = o.lo_ < lo_ ? o.lo_ : lo_;
        hi_ = o.hi_ > hi_ ? o.hi_ : hi_;
    }
    Bounds3 bounds() const { return {{lo_[0], lo_[1], lo_[2]}, {hi_[0], hi_[1], hi_[2]}}; }
    // As Bounds3::area(): 0 for an empty box.
    float area() const {
        if (!(lo_[0] <= hi_[0] && lo_[1] <= hi_[1] && lo_[2] <= hi_[2])) return 0.0f;
        const F4 d = hi_ - lo_;
        return 2.0f * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]);
    }

private:
    static F4 load(const unsigned char* p) {
        F4 v;
        std::memcpy(&v, p, sizeof v);
        return v;
    }
    F4 lo_ = {kInfinity, kInfinity, kInfinity, kInfinity};
    F4 hi_ = {-kInfinity, -kInfinity, -kInfinity, -kInfinity};
};

// Calls f(std::integral_constant<int, axis>{}): code run per primitive then reads a
// compile-time axis instead of branching on a runtime one at every access.
template <class F>
decltype(auto) with_axis(int axis, F&& f) {
    switch (axis) {
        case 0: return f(std::integral_constant<int, 0>{});
        case 1: return f(std::integral_constant<int, 1>{});
        default: return f(std::integral_constant<int, 2>{});
    }
}

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
    // As many references as the range, free for the strategy to use (out-of-place
    // partitioning); allocated once per build.
    std::span<BvhPrimRef> scratch;
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
    if constexpr (requires { S::kMayStopEarly; }) return S::kMayStopEarly;
    else return false;
}

inline void fit(std::span<const BvhPrimRef> refs, Bounds3& bounds, Bounds3& centroid_bounds) {
    // Two independent accumulator pairs halve the chain of dependent min/max operations.
    BvhBoxAccumulator b[2], cb[2];
    const size_t n = refs.size();
    for (size_t i = 0; i + 1 < n; i += 2) {
        b[0].extend(refs[i], cb[0]);
        b[1].extend(refs[i + 1], cb[1]);
    }
    if (n % 2) b[0].extend(refs[n - 1], cb[0]);
    b[0].extend(b[1]);
    cb[0].extend(cb[1]);
    bounds = b[0].bounds();
    centroid_bounds = cb[0].bounds();
}

// Splits a range into two halves by count along `axis` (the object median; also the
// fallback for ranges a strategy cannot separate): afterwards no centroid in [0, mid)
// lies above one in [mid, n), as with std::nth_element. Large ranges are not selected
// by nth_element directly (several branchy passes moving 28-byte references): one pass
// counts the centroids into equal-width bins between lo and hi, the bin holding the
// median is found from the counts, one branch-free pass moves the references bin-wise
// into three groups (below, in, above that bin) through `scratch`, and nth_element
// finishes inside the median's bin only. The binning is monotonic in the centroid, so
// the three groups are ordered.
// Measured (session 4, callgrind, the bunny's median build): this function is 61% of the
// build's instructions, the children's fit 16%, the copy back from scratch 17%,
// FlatBvh::finalize 9%. Leaving the result in scratch and ping-ponging the two buffers
// (no copy back, the same tree byte for byte) saved 11% of the instructions but no
// time beyond noise on the conference or the dragon (build / Embree 0.67-0.72 either
// way): the passes over the 28-byte references are bound by memory traffic, not
// instructions, so it was not kept.
inline BvhSplit split_equal_counts(std::span<BvhPrimRef> refs, std::span<BvhPrimRef> scratch, int axis, float lo,
                                   float hi) {
    const size_t n = refs.size(), mid = n / 2;
    with_axis(axis, [&](auto a) {
        auto by_centroid = [a](const BvhPrimRef& x, const BvhPrimRef& y) { return x.centroid(a) < y.centroid(a); };
        constexpr uint32_t kMaxBins = 256;
        if (n <= 3) {  // half of all nodes of a full tree: a compare-exchange network
            auto order = [&](size_t i, size_t j) {
                if (by_centroid(refs[j], refs[i])) std::swap(refs[i], refs[j]);
            };
            if (n >= 2) order(0, 1);
            if (n == 3) {
                order(1, 2);
                order(0, 1);
            }
            return;
        }
        if (n < 16 || !(hi > lo)) {
            std::nth_element(refs.begin(), refs.begin() + mid, refs.end(), by_centroid);
            return;
        }
        const uint32_t bins = uint32_t(std::min<size_t>(kMaxBins, n / 4));  // ~4 per bin
        const float scale = float(bins) * (1.0f - 1e-6f) / (hi - lo);
        auto bin_of = [=](const BvhPrimRef& r) {
            return uint32_t(std::min(float(bins - 1), std::max(0.0f, (r.centroid(a) - lo) * scale)));
        };
        uint32_t counts[kMaxBins] = {};
        for (const BvhPrimRef& r : refs) ++counts[bin_of(r)];
        uint32_t median_bin = 0, below = 0;
        while (below + counts[median_bin] <= mid) below += counts[median_bin++];
        // Three-way scatter: group 0 below the median's bin, 1 in it, 2 above it.
        size_t next[3] = {0, below, below + counts[median_bin]};
        for (const BvhPrimRef& r : refs) {
            const uint32_t b = bin_of(r);
            const int group = int(b >= median_bin) + int(b > median_bin);
            scratch[next[group]++] = r;
        }
        std::copy(scratch.begin(), scratch.begin() + ptrdiff_t(n), refs.begin());
        std::nth_element(refs.begin() + ptrdiff_t(below), refs.begin() + ptrdiff_t(mid),
                         refs.begin() + ptrdiff_t(below + counts[median_bin]), by_centroid);
    });
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
    std::vector<BvhPrimRef> scratch(refs.size());
    const uint32_t n = uint32_t(refs.size());
    if (n == 0) {
        bvh.finalize(scene);
        return bvh;
    }
    bvh.nodes.resize(2 * size_t(n) - 1);  // a binary tree with non-empty leaves has at most 2n-1 nodes
    uint32_t node_count = 0;

    struct Range {
        uint32_t begin, end, depth;
        uint32_t parent;  // node whose second child this range becomes (kInvalidId: none)
        Bounds3 bounds, centroid_bounds;
    };
    std::vector<Range> pending;  // second children still to build; at most one per level
    Range range{0, n, 0, kInvalidId, {}, {}};
    detail::fit(refs, range.bounds, range.centroid_bounds);

    for (;;) {
        const uint32_t index = node_count++;
        if (range.parent != kInvalidId) bvh.nodes[range.parent].index = index;
        const uint32_t count = range.end - range.begin;
        const std::span<BvhPrimRef> span(refs.data() + range.begin, count);

        // Leaf or split?
        std::optional<BvhSplit> split;
        const bool small = count <= settings.max_prims;
        if (count > 1 && range.depth < settings.max_depth && (!small || kMayStopEarly)) {
            const Vec3 extent = range.centroid_bounds.diagonal();
            const int axis = settings.axis == BvhAxisRule::longest ? max_axis(extent) : int(range.depth % 3);
            const std::span<BvhPrimRef> span_scratch(scratch.data() + range.begin, count);
            if (extent[axis] > 0.0f)
                split = strategy(span, {range.bounds, range.centroid_bounds, axis, range.depth, small, span_scratch});
            if (split && (split->mid == 0 || split->mid >= count))
                throw std::logic_error("bvh: split strategy returned an empty side");
            if (!split && !small) {
                ++counts.degenerate_splits;
                const int longest = max_axis(extent);
                split = detail::split_equal_counts(span, span_scratch, longest, range.centroid_bounds.lower[longest],
                                                   range.centroid_bounds.upper[longest]);
            }
        } else if (!small) {
            ++counts.forced_leaves;  // at max_depth with more than max_prims primitives
        }

        if (!split) {
            bvh.nodes[index] = BvhNode::leaf(range.bounds, range.begin, count);
            if (pending.empty()) break;
            range = pending.back();
            pending.pop_back();
            continue;
        }
        bvh.nodes[index] = BvhNode::inner(range.bounds, 0, split->axis);  // second child patched later
        const uint32_t mid = range.begin + uint32_t(split->mid);
        Range first{range.begin, mid, range.depth + 1, kInvalidId, {}, {}};
        Range second{mid, range.end, range.depth + 1, index, {}, {}};
        detail::fit(std::span<const BvhPrimRef>(refs.data() + first.begin, first.end - first.begin), first.bounds,
                    first.centroid_bounds);
        detail::fit(std::span<const BvhPrimRef>(refs.data() + second.begin, second.end - second.begin), second.bounds,
                    second.centroid_bounds);
        pending.push_back(second);
        range = first;
    }

    bvh.nodes.resize(node_count);
    bvh.nodes.shrink_to_fit();  // leaves of several primitives leave part of the 2n-1 unused
    bvh.prim_ids.resize(n);
    for (uint32_t i = 0; i < n; ++i) bvh.prim_ids[i] = refs[i].id;
    bvh.finalize(scene);
    return bvh;
}

}  // namespace accelbench
