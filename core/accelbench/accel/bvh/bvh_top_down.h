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
//    equal halves along the longest centroid axis instead (EqualCountSplitter), counted
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
#include <new>
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

// What the builder moves for a strategy that looks at centroids only (BvhCentroidSplit
// below: the median): the centroid (Scene::centroids, the same floats as
// BvhPrimRef::centroid) and the index, 16 bytes, one vector load. The nodes' boxes are
// then not fitted top-down but once, bottom-up, after the tree is made: a leaf's box is
// the union of its triangles' boxes, an inner node's the union of its children's — the
// same unions of the same boxes, so the same floats.
struct alignas(16) BvhCentroidRef {
    Vec3 c;
    uint32_t id;

    float centroid(int axis) const { return c[axis]; }
};
static_assert(sizeof(BvhCentroidRef) == 16);

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
    // r's centroid in lanes 0-2 (the arithmetic of BvhPrimRef::centroid, so the same
    // floats); lane 3 carries no meaning.
    static F4 centroid(const BvhPrimRef& r) {
        return 0.5f *
            (load(reinterpret_cast<const unsigned char*>(&r)) +
             load(reinterpret_cast<const unsigned char*>(&r) + sizeof(Vec3)));
    }
    // Extends this box by r's centroid (lane 3 holds the id's bits: never read back).
    void extend(const BvhCentroidRef& r) {
        const F4 c = load(reinterpret_cast<const unsigned char*>(&r));
        lo_ = c < lo_ ? c : lo_;
        hi_ = c > hi_ ? c : hi_;
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

// What a strategy is asked about one range of references of type Ref (BvhPrimRef or
// BvhCentroidRef).
template <class Ref>
struct BvhRangeRequest {
    Bounds3 bounds;           // of the primitives (BvhPrimRef only: left empty for BvhCentroidRef)
    Bounds3 centroid_bounds;  // of their centroids; its extent along `axis` is > 0
    int axis;                 // chosen by the axis rule
    uint32_t depth;
    // True when the range is small enough (<= max_prims) to be a leaf: a strategy that
    // may stop early (SAH) answers "no split" when a leaf is cheaper.
    bool leaf_allowed;
    // As many references as the range, free for the strategy to use (out-of-place
    // partitioning); allocated once per build.
    std::span<Ref> scratch;
};
using BvhSplitRequest = BvhRangeRequest<BvhPrimRef>;

// A strategy's answer: refs[0, mid) go to the first child, refs[mid, n) to the second,
// with 0 < mid < n; `axis` is stored in the node. A strategy that partitions out of place
// may leave the result in the request's scratch instead of copying it back
// (`in_scratch`; refs is then the scratch of the children), and one that can compute the
// children's boxes while partitioning hands them over (`fitted`: centroid_bounds, and
// bounds for BvhPrimRef), so the builder does not read the references again to fit them.
struct BvhSplit {
    size_t mid;
    int axis;
    bool in_scratch = false;
    bool fitted = false;
    Bounds3 bounds[2] = {}, centroid_bounds[2] = {};  // first and second child, when fitted
};

// A split strategy is a callable
//     std::optional<BvhSplit> operator()(std::span<Ref> refs, const BvhRangeRequest<Ref>&)
// that may reorder refs and answers where the range splits, or std::nullopt when it
// cannot separate the range (or, with leaf_allowed, prefers a leaf). Ref is BvhPrimRef,
// or BvhCentroidRef for a strategy that declares
//     using Ref = BvhCentroidRef;
// (it sees centroids only, and request.bounds is empty). A strategy with
//     static constexpr bool kMayStopEarly = true;
// is also asked about ranges of 2..max_prims primitives (SAH termination); others see
// only ranges above max_prims.
template <class S>
struct BvhStrategyRef {
    using type = BvhPrimRef;
};
template <class S>
requires requires { typename S::Ref; }
struct BvhStrategyRef<S> {
    using type = typename S::Ref;
};

template <class Strategy>
concept BvhSplitStrategy = requires(Strategy s, std::span<typename BvhStrategyRef<Strategy>::type> refs,
                                    const BvhRangeRequest<typename BvhStrategyRef<Strategy>::type>& r) {
    { s(refs, r) } -> std::same_as<std::optional<BvhSplit>>;
};

namespace detail {

template <class S>
constexpr bool may_stop_early() {
    if constexpr (requires { S::kMayStopEarly; }) return S::kMayStopEarly;
    else return false;
}

// The box and the centroid box of a range. For BvhCentroidRef the centroid box only:
// `bounds` is left empty and the node boxes are made bottom-up after the build
// (fit_bottom_up).
template <class Ref>
inline void fit(std::span<const Ref> refs, Bounds3& bounds, Bounds3& centroid_bounds) {
    constexpr bool kBoxes = std::is_same_v<Ref, BvhPrimRef>;
    // Two independent accumulator pairs halve the chain of dependent min/max operations.
    BvhBoxAccumulator b[2], cb[2];
    auto add = [&](const Ref& r, int k) {
        if constexpr (kBoxes) b[k].extend(r, cb[k]);
        else cb[k].extend(r);
    };
    const size_t n = refs.size();
    for (size_t i = 0; i + 1 < n; i += 2) {
        add(refs[i], 0);
        add(refs[i + 1], 1);
    }
    if (n % 2) add(refs[n - 1], 0);
    b[0].extend(b[1]);
    cb[0].extend(cb[1]);
    bounds = kBoxes ? b[0].bounds() : Bounds3{};
    centroid_bounds = cb[0].bounds();
}

// The boxes of a tree built from BvhCentroidRef, bottom-up (children follow their parent
// in the array): a leaf's from its triangles' corners, which finalize() has just copied in
// leaf order (a sequential read; the same floats as Scene::prim_bounds, which extends a
// box by the three corners in this order), an inner node's from its children's.
inline void fit_bottom_up(FlatBvh& bvh) {
    for (size_t i = bvh.nodes.size(); i-- > 0;) {
        BvhNode& node = bvh.nodes[i];
        Bounds3 b;
        if (node.is_leaf()) {
            for (uint32_t slot = node.first_prim(); slot < node.first_prim() + node.prim_count(); ++slot) {
                const LeafTriangle& t = bvh.triangles[slot];
                b.extend(t.p0);
                b.extend(t.p1);
                b.extend(t.p2);
            }
        } else {
            b = bvh.nodes[i + 1].bounds;
            b.extend(bvh.nodes[node.second_child()].bounds);
        }
        node.bounds = b;
    }
}

// Splits a range into two halves by count along `axis` (the object median; also the
// fallback for ranges a strategy cannot separate): afterwards no centroid in [0, mid)
// lies above one in [mid, n), as with std::nth_element. Large ranges are not selected
// by nth_element directly (several branchy passes moving 28-byte references): one pass
// counts the centroids into equal-width bins between lo and hi, the bin holding the
// median is found from the counts, one branch-free pass moves the references bin-wise
// into three groups (below, in, above that bin) into `scratch`, and nth_element
// finishes inside the median's bin only. The binning is monotonic in the centroid, so
// the three groups are ordered.
//
// The counting pass also accumulates each bin's box and centroid box and remembers each
// reference's bin (one byte), so the children's boxes are the union of the bins below
// and above the median's plus the median bin's few references (fitted after
// nth_element), the scatter reads the bin instead of recomputing it, and the result stays
// in scratch (in_scratch: the builder swaps the two buffers for the children) instead of
// being copied back. The references are moved in exactly the order of the earlier
// in-place version (42f25d3) and nth_element sees the same sequence, so the tree is
// the same byte for byte (bvh_test MedianBuildIsInPlaceTreeByteForByte) — except that
// a box coordinate that is zero may come out as +0 where the old fit gave -0 or the
// reverse (min/max keep the first of two equal values, and the union runs in another
// order), which no comparison can tell apart.
// Measured (callgrind, one median build): the in-place version (28-byte
// references, fit of each child in a separate pass, copy back from scratch) spent 110M
// instructions on the bunny, 591M on the conference; with this one on 16-byte
// BvhCentroidRef, the node boxes made bottom-up (fit_bottom_up) and no copy back, 99M and
// 521M. Build / Embree (accel_bench, interleaved, 5 repetitions, load 9-11 on the 2
// cores): bunny 0.55-0.56 -> 0.48-0.49, conference 0.67-0.71 -> 0.66-0.67. What did not
// pay: fitting the children from per-bin boxes accumulated in the counting pass (on
// 28-byte references: 113M instructions, no time gained), and taking a leaf's box from
// Scene::prim_bounds through its index (a random read per leaf, the bunny 5% slower
// than the in-place version) instead of from the triangles finalize() copies in leaf order.
// A branch-free introselect and a masked scatter were measured and not adopted:
// docs/decisions.md, "Binary BVH build".
template <class Ref>
class EqualCountSplitter {
public:
    BvhSplit operator()(std::span<Ref> refs, std::span<Ref> scratch, int axis, float lo, float hi) {
        const size_t n = refs.size(), mid = n / 2;
        return with_axis(axis, [&](auto a) {
            auto by_centroid = [a](const Ref& x, const Ref& y) { return x.centroid(a) < y.centroid(a); };
            if (n <= 3) {  // half of all nodes of a full tree: a compare-exchange network
                auto order = [&](size_t i, size_t j) {
                    if (by_centroid(refs[j], refs[i])) std::swap(refs[i], refs[j]);
                };
                if (n >= 2) order(0, 1);
                if (n == 3) {
                    order(1, 2);
                    order(0, 1);
                }
                return BvhSplit{mid, axis};
            }
            if (n < 16 || !(hi > lo)) {
                std::nth_element(refs.begin(), refs.begin() + ptrdiff_t(mid), refs.end(), by_centroid);
                return BvhSplit{mid, axis};
            }
            return split_binned(a, refs.data(), scratch.data(), n, lo, hi);
        });
    }

private:
    // The binned selection of ranges of 16 or more references. Everything the loops use
    // is a local: the per-reference byte store would otherwise make the compiler reload
    // every captured value through memory at each reference (a char store may alias
    // anything), 38 instructions per reference in the counting loop.
    template <class Axis>
    BvhSplit split_binned(Axis a, const Ref* refs, Ref* scratch, size_t n, float lo, float hi) {
        const size_t mid = n / 2;
        const uint32_t bins = uint32_t(std::min<size_t>(kMaxBins, n / 4));  // ~4 per bin
        const float scale = float(bins) * (1.0f - 1e-6f) / (hi - lo);
        const float last_bin = float(bins - 1);
        if (bin_.size() < n) bin_.resize(n);  // the root's range is the largest
        uint8_t* const bin = bin_.data();
        uint32_t* const counts = counts_;
        BvhBoxAccumulator* const boxes = boxes_;
        BvhBoxAccumulator* const centroids = centroids_;
        // The bins are empty on entry (left empty below).
        for (size_t i = 0; i < n; ++i) {
            const Ref& r = refs[i];
            const uint32_t b = uint32_t(std::min(last_bin, std::max(0.0f, (r.centroid(a) - lo) * scale)));
            bin[i] = uint8_t(b);
            ++counts[b];
            if constexpr (kBoxes) boxes[b].extend(r, centroids[b]);
            else centroids[b].extend(r);
        }
        uint32_t median_bin = 0, below = 0;
        while (below + counts[median_bin] <= mid) below += counts[median_bin++];
        const uint32_t in_median = counts[median_bin];
        BvhBoxAccumulator child_box[2], child_centroids[2];  // first, second child
        for (uint32_t b = 0; b < bins; ++b) {
            if (b != median_bin) {
                if constexpr (kBoxes) child_box[b > median_bin].extend(boxes[b]);
                child_centroids[b > median_bin].extend(centroids[b]);
            }
            if constexpr (kBoxes) boxes[b] = BvhBoxAccumulator{};
            centroids[b] = BvhBoxAccumulator{};
            counts[b] = 0;
        }
        // Three-way scatter: group 0 below the median's bin, 1 in it, 2 above it. The
        // three write positions are selected in registers: kept in an array indexed by the
        // group, each store's address waited for the previous increment through memory
        // (store-to-load forwarding) whenever two references in a row went the same way.
        size_t next0 = 0, next1 = below, next2 = below + in_median;
        for (size_t i = 0; i < n; ++i) {
            const uint32_t b = bin[i];
            const bool above = b > median_bin, in = b == median_bin;
            const size_t dst = above ? next2 : (in ? next1 : next0);
            scratch[dst] = refs[i];
            next2 += above;
            next1 += in;
            next0 += !above & !in;
        }
        auto by_centroid = [a](const Ref& x, const Ref& y) { return x.centroid(a) < y.centroid(a); };
        Ref* const first = scratch + below;
        Ref* const last = first + in_median;
        std::nth_element(first, scratch + mid, last, by_centroid);
        for (Ref* r = first; r != last; ++r) {
            const bool second = r >= scratch + mid;
            if constexpr (kBoxes) child_box[second].extend(*r, child_centroids[second]);
            else child_centroids[second].extend(*r);
        }
        BvhSplit split{mid, Axis::value, true, true};
        for (int c = 0; c < 2; ++c) {
            split.bounds[c] = child_box[c].bounds();
            split.centroid_bounds[c] = child_centroids[c].bounds();
        }
        return split;
    }

    static constexpr uint32_t kMaxBins = 256;                        // a bin index fits a byte
    static constexpr bool kBoxes = std::is_same_v<Ref, BvhPrimRef>;  // BvhCentroidRef: centroid boxes only
    BvhBoxAccumulator boxes_[kBoxes ? kMaxBins : 1], centroids_[kMaxBins];
    uint32_t counts_[kMaxBins] = {};
    std::vector<uint8_t> bin_;  // bin of each reference of the range being split
};

}  // namespace detail

// Object median (report 2.2.1): half the primitives on each side, by centroid order.
// Balanced by construction, blind to the primitives' sizes and to empty space. The
// median BVH's split, and the tree of the LBVH's build=median (lbvh.h).
struct BvhMedianSplit {
    using Ref = BvhCentroidRef;  // the median looks at centroids only
    std::optional<BvhSplit> operator()(std::span<Ref> refs, const BvhRangeRequest<Ref>& r) {
        return equal_counts(refs, r.scratch, r.axis, r.centroid_bounds.lower[r.axis], r.centroid_bounds.upper[r.axis]);
    }
    detail::EqualCountSplitter<Ref> equal_counts;
};

// The references the builder starts from: one per scene triangle, in scene order.
inline void put_refs(const Scene& scene, BvhPrimRef* out) {
    for (size_t i = 0; i < scene.triangle_count(); ++i) out[i] = {scene.prim_bounds[i], uint32_t(i)};
}
inline void put_refs(const Scene& scene, BvhCentroidRef* out) {
    for (size_t i = 0; i < scene.triangle_count(); ++i) out[i] = {scene.centroids[i], uint32_t(i)};
}

namespace detail {

// n references in memory that is not initialised: the builder writes each one before it
// reads it. std::vector<Ref>(n) constructs every reference first (Vec3's members have
// initialisers: a loop of stores) for both buffers the build moves references between.
// With these and FlatBvh::finalize appending its triangles instead of resize() then
// overwrite (callgrind, one median build, x86-64-v3): bunny 98.1M -> 95.3M
// instructions, L1 write misses 490k -> 417k; conference 525M -> 512M, 2.53M -> 2.18M
// (LL write misses 2.14M -> 1.79M). Build / Embree (accel_bench, old and new binary back
// to back twice, load 6-11): bunny 0.45, 0.46 -> 0.45, 0.45; conference 0.57, 0.60 ->
// 0.58, 0.57; dragon 0.57, 0.52 -> 0.54, 0.56: no change beyond the noise. A reference
// is a trivially copyable aggregate, an implicit-lifetime type: allocating the storage
// creates it.
template <class Ref>
class RefBuffer {
    static_assert(std::is_trivially_copyable_v<Ref> && std::is_trivially_destructible_v<Ref>);

public:
    explicit RefBuffer(size_t n)
        : data_(
              static_cast<Ref*>(::operator new(std::max<size_t>(n, 1) * sizeof(Ref), std::align_val_t(alignof(Ref))))) {
    }
    ~RefBuffer() { ::operator delete(data_, std::align_val_t(alignof(Ref))); }
    RefBuffer(const RefBuffer&) = delete;
    RefBuffer& operator=(const RefBuffer&) = delete;
    Ref* data() const { return data_; }

private:
    Ref* data_;
};

}  // namespace detail

template <BvhSplitStrategy Strategy>
FlatBvh build_bvh_top_down(const Scene& scene, const BvhTopDownSettings& settings, Strategy& strategy,
                           BvhTopDownCounts& counts) {
    constexpr bool kMayStopEarly = detail::may_stop_early<Strategy>();
    using Ref = typename BvhStrategyRef<Strategy>::type;
    constexpr bool kCentroidsOnly = std::is_same_v<Ref, BvhCentroidRef>;  // node boxes made bottom-up
    if (scene.triangle_count() > BvhNode::kMaxLeafPrims)
        throw std::runtime_error("bvh: scene '" + scene.name + "' has more triangles than a BVH node can count");
    FlatBvh bvh;
    counts = {};
    const uint32_t n = uint32_t(scene.triangle_count());
    const detail::RefBuffer<Ref> refs(n), scratch(n);
    put_refs(scene, refs.data());
    if (n == 0) {
        bvh.finalize(scene);
        return bvh;
    }
    // A range's references are in one of two buffers: a strategy that partitions out of
    // place leaves its children in the other one (BvhSplit::in_scratch), which is then
    // their scratch, so nothing is copied back.
    Ref* const buffers[2] = {refs.data(), scratch.data()};
    bvh.nodes.reserve(2 * size_t(n) - 1);  // a binary tree with non-empty leaves has at most 2n-1 nodes
    bvh.prim_ids.resize(n);
    detail::EqualCountSplitter<Ref> equal_counts;  // the fallback for ranges the strategy cannot separate

    struct Range {
        uint32_t begin, end, depth;
        uint32_t parent;  // node whose second child this range becomes (kInvalidId: none)
        uint32_t buffer;  // index into buffers
        Bounds3 bounds, centroid_bounds;
    };
    std::vector<Range> pending;  // second children still to build; at most one per level
    Range range{0, n, 0, kInvalidId, 0, {}, {}};
    detail::fit<Ref>(std::span<const Ref>(refs.data(), n), range.bounds, range.centroid_bounds);

    for (;;) {
        const uint32_t index = uint32_t(bvh.nodes.size());
        if (range.parent != kInvalidId) bvh.nodes[range.parent].index = index;
        const uint32_t count = range.end - range.begin;
        const std::span<Ref> span(buffers[range.buffer] + range.begin, count);

        // Leaf or split?
        std::optional<BvhSplit> split;
        const bool small = count <= settings.max_prims;
        if (count > 1 && range.depth < settings.max_depth && (!small || kMayStopEarly)) {
            const Vec3 extent = range.centroid_bounds.diagonal();
            const int axis = settings.axis == BvhAxisRule::longest ? max_axis(extent) : int(range.depth % 3);
            const std::span<Ref> span_scratch(buffers[range.buffer ^ 1] + range.begin, count);
            if (extent[axis] > 0.0f)
                split = strategy(span, {range.bounds, range.centroid_bounds, axis, range.depth, small, span_scratch});
            if (split && (split->mid == 0 || split->mid >= count))
                throw std::logic_error("bvh: split strategy returned an empty side");
            if (!split && !small) {
                ++counts.degenerate_splits;
                const int longest = max_axis(extent);
                split = equal_counts(span, span_scratch, longest, range.centroid_bounds.lower[longest],
                                     range.centroid_bounds.upper[longest]);
            }
        } else if (!small) {
            ++counts.forced_leaves;  // at max_depth with more than max_prims primitives
        }

        if (!split) {
            for (uint32_t i = 0; i < count; ++i) bvh.prim_ids[range.begin + i] = span[i].id;
            bvh.nodes.push_back(BvhNode::leaf(range.bounds, range.begin, count));  // kCentroidsOnly: fitted below
            if (pending.empty()) break;
            range = pending.back();
            pending.pop_back();
            continue;
        }
        bvh.nodes.push_back(BvhNode::inner(range.bounds, 0, split->axis));  // second child patched later
        const uint32_t mid = range.begin + uint32_t(split->mid);
        const uint32_t buffer = range.buffer ^ uint32_t(split->in_scratch);
        Range first{range.begin, mid, range.depth + 1, kInvalidId, buffer, {}, {}};
        Range second{mid, range.end, range.depth + 1, index, buffer, {}, {}};
        if (split->fitted) {
            first.bounds = split->bounds[0];
            first.centroid_bounds = split->centroid_bounds[0];
            second.bounds = split->bounds[1];
            second.centroid_bounds = split->centroid_bounds[1];
        } else {
            detail::fit(std::span<const Ref>(buffers[buffer] + first.begin, first.end - first.begin), first.bounds,
                        first.centroid_bounds);
            detail::fit(std::span<const Ref>(buffers[buffer] + second.begin, second.end - second.begin), second.bounds,
                        second.centroid_bounds);
        }
        pending.push_back(second);
        range = first;
    }

    bvh.nodes.shrink_to_fit();  // leaves of several primitives leave part of the 2n-1 unused
    bvh.finalize(scene);
    if constexpr (kCentroidsOnly) detail::fit_bottom_up(bvh);
    return bvh;
}

}  // namespace accelbench
