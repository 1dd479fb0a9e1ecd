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
#include "accelbench/base/parallel.h"
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
    bool parallel = false;  // on the build's threads (called inside BuildThreads::run): the same tree
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
    // A large range of a build on several threads: the strategy may spread its work over the
    // build's threads (base/parallel.h), and must answer as on one.
    bool parallel = false;
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
// The box and centroid box of refs in two accumulator pairs, one for the even references
// and one for the odd (two independent chains of dependent min/max operations, half as long).
template <class Ref>
struct FitAccumulators {
    BvhBoxAccumulator b[2], cb[2];

    // refs, the first of which has an even index in the range being fitted.
    void add(std::span<const Ref> refs) {
        auto one = [&](const Ref& r, int k) {
            if constexpr (std::is_same_v<Ref, BvhPrimRef>) b[k].extend(r, cb[k]);
            else cb[k].extend(r);
        };
        const size_t n = refs.size();
        for (size_t i = 0; i + 1 < n; i += 2) {
            one(refs[i], 0);
            one(refs[i + 1], 1);
        }
        if (n % 2) one(refs[n - 1], 0);
    }
    void add(const FitAccumulators& o) {
        for (int k = 0; k < 2; ++k) {
            b[k].extend(o.b[k]);
            cb[k].extend(o.cb[k]);
        }
    }
    void result(Bounds3& bounds, Bounds3& centroid_bounds) {
        b[0].extend(b[1]);
        cb[0].extend(cb[1]);
        bounds = std::is_same_v<Ref, BvhPrimRef> ? b[0].bounds() : Bounds3{};
        centroid_bounds = cb[0].bounds();
    }
};

template <class Ref>
inline void fit(std::span<const Ref> refs, Bounds3& bounds, Bounds3& centroid_bounds) {
    FitAccumulators<Ref> acc;
    acc.add(refs);
    acc.result(bounds, centroid_bounds);
}

// fit() on the build's threads: blocks of an even size, each accumulated as fit() does, the
// blocks' even and odd accumulators merged in order: fit()'s floats (base/parallel.h).
template <class Ref>
inline void fit_parallel(std::span<const Ref> refs, Bounds3& bounds, Bounds3& centroid_bounds, bool parallel) {
    constexpr size_t kBlock = 1 << 15;
    if (!parallel || refs.size() < 2 * kBlock) return fit(refs, bounds, centroid_bounds);
    std::vector<FitAccumulators<Ref>> parts(block_count(refs.size(), kBlock));
    for_blocks(true, refs.size(), kBlock,
               [&](size_t k, size_t begin, size_t end) { parts[k].add(refs.subspan(begin, end - begin)); });
    for (size_t k = 1; k < parts.size(); ++k) parts[0].add(parts[k]);
    parts[0].result(bounds, centroid_bounds);
}

// The boxes of a tree built from BvhCentroidRef, bottom-up (children follow their parent
// in the array): a leaf's from its triangles' corners, which finalize() has just copied in
// leaf order (a sequential read; the same floats as Scene::prim_bounds, which extends a
// box by the three corners in this order), an inner node's from its children's.
// The nodes [begin, end), from the back: every node's children after it within the range.
inline void fit_bottom_up(FlatBvh& bvh, size_t begin, size_t end) {
    for (size_t i = end; i-- > begin;) {
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

// The subtree of node i; on the build's threads, the two children of a large one at once
// (each box is the same union whoever computes it).
inline void fit_subtree_bottom_up(FlatBvh& bvh, size_t i, bool parallel) {
    constexpr size_t kSerial = 1 << 15;  // nodes
    const size_t end = subtree_end(bvh, i);
    if (!parallel || end - i < kSerial) return fit_bottom_up(bvh, i, end);
    BvhNode& node = bvh.nodes[i];
    fork_join(
        true, [&] { fit_subtree_bottom_up(bvh, i + 1, true); },
        [&] { fit_subtree_bottom_up(bvh, node.second_child(), true); });
    Bounds3 b = bvh.nodes[i + 1].bounds;
    b.extend(bvh.nodes[node.second_child()].bounds);
    node.bounds = b;
}

inline void fit_bottom_up(FlatBvh& bvh, bool parallel) {
    if (!bvh.nodes.empty()) fit_subtree_bottom_up(bvh, 0, parallel);
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
    // `parallel`: a large range on the build's threads (the counting and the scatter in
    // blocks, merged in order: the same split, base/parallel.h).
    BvhSplit operator()(std::span<Ref> refs, std::span<Ref> scratch, int axis, float lo, float hi,
                        bool parallel = false) {
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
            return split_binned(a, refs.data(), scratch.data(), n, lo, hi, parallel);
        });
    }

private:
    // The binned selection of ranges of 16 or more references. Everything the loops use
    // is a local: the per-reference byte store would otherwise make the compiler reload
    // every captured value through memory at each reference (a char store may alias
    // anything), 38 instructions per reference in the counting loop.
    template <class Axis>
    BvhSplit split_binned(Axis a, const Ref* refs, Ref* scratch, size_t n, float lo, float hi, bool parallel) {
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
        struct Part {
            uint32_t counts[kMaxBins] = {};
            BvhBoxAccumulator boxes[kBoxes ? kMaxBins : 1], centroids[kMaxBins];
        };
        std::vector<Part> parts;  // parallel: each block's bins
        if (!parallel) {
            count_range(a, refs, bin, 0, n, lo, scale, last_bin, counts, boxes, centroids);
        } else {
            parts.resize(block_count(n, kParallelBlock));
            for_blocks(true, n, kParallelBlock, [&](size_t k, size_t begin, size_t end) {
                count_range(a, refs, bin, begin, end, lo, scale, last_bin, parts[k].counts, parts[k].boxes,
                            parts[k].centroids);
            });
            for (const Part& p : parts)
                for (uint32_t b = 0; b < bins; ++b) {
                    counts[b] += p.counts[b];
                    if constexpr (kBoxes) boxes[b].extend(p.boxes[b]);
                    centroids[b].extend(p.centroids[b]);
                }
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
        if (!parallel) {
            scatter_range(refs, bin, scratch, 0, n, median_bin, 0, below, below + in_median);
        } else {
            // Each block's groups start after the earlier blocks' groups.
            std::vector<size_t> starts(3 * parts.size());
            size_t next[3] = {0, below, below + in_median};
            for (size_t k = 0; k < parts.size(); ++k) {
                uint32_t group[3] = {0, parts[k].counts[median_bin], 0};
                for (uint32_t b = 0; b < bins; ++b)
                    if (b != median_bin) group[b > median_bin ? 2 : 0] += parts[k].counts[b];
                for (int g = 0; g < 3; ++g) {
                    starts[3 * k + size_t(g)] = next[g];
                    next[g] += group[g];
                }
            }
            for_blocks(true, n, kParallelBlock, [&](size_t k, size_t begin, size_t end) {
                scatter_range(refs, bin, scratch, begin, end, median_bin, starts[3 * k], starts[3 * k + 1],
                              starts[3 * k + 2]);
            });
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

    // The counting loop over refs [begin, end) into the given bins. Every value it reads is
    // a parameter (a local): see split_binned.
    template <class Axis>
    static void count_range(Axis a, const Ref* refs, uint8_t* bin, size_t begin, size_t end, float lo, float scale,
                            float last_bin, uint32_t* counts, BvhBoxAccumulator* boxes, BvhBoxAccumulator* centroids) {
        for (size_t i = begin; i < end; ++i) {
            const Ref& r = refs[i];
            const uint32_t b = uint32_t(std::min(last_bin, std::max(0.0f, (r.centroid(a) - lo) * scale)));
            bin[i] = uint8_t(b);
            ++counts[b];
            if constexpr (kBoxes) boxes[b].extend(r, centroids[b]);
            else centroids[b].extend(r);
        }
    }

    // The three-way scatter of refs [begin, end), the groups' next positions starting at
    // next0, next1, next2.
    static void scatter_range(const Ref* refs, const uint8_t* bin, Ref* scratch, size_t begin, size_t end,
                              uint32_t median_bin, size_t next0, size_t next1, size_t next2) {
        for (size_t i = begin; i < end; ++i) {
            const uint32_t b = bin[i];
            const bool above = b > median_bin, in = b == median_bin;
            const size_t dst = above ? next2 : (in ? next1 : next0);
            scratch[dst] = refs[i];
            next2 += above;
            next1 += in;
            next0 += !above & !in;
        }
    }

    static constexpr uint32_t kMaxBins = 256;                        // a bin index fits a byte
    static constexpr size_t kParallelBlock = 1 << 14;                // references per block
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
        return equal_counts(refs, r.scratch, r.axis, r.centroid_bounds.lower[r.axis], r.centroid_bounds.upper[r.axis],
                            r.parallel);
    }
    detail::EqualCountSplitter<Ref> equal_counts;
};

// The references the builder starts from: one per scene triangle, in scene order.
inline void put_refs(const Scene& scene, BvhPrimRef* out, bool parallel) {
    for_blocks(parallel, scene.triangle_count(), 1 << 14, [&](size_t, size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) out[i] = {scene.prim_bounds[i], uint32_t(i)};
    });
}
inline void put_refs(const Scene& scene, BvhCentroidRef* out, bool parallel) {
    for_blocks(parallel, scene.triangle_count(), 1 << 14, [&](size_t, size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) out[i] = {scene.centroids[i], uint32_t(i)};
    });
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

namespace detail {

// What one task of the build writes.
struct TopDownOutput {
    BvhPiece& piece;  // in place: the whole node array, shared by every task
    BvhTopDownCounts counts;
    uint32_t deepest = 0;  // deepest leaf so far (root: 0)
};

// The build's loop over one subtree, on one task; on several threads it hands a large second
// child's subtree to another task (build_bvh_top_down).
template <class Strategy>
class TopDownBuild {
public:
    using Ref = typename BvhStrategyRef<Strategy>::type;
    static constexpr bool kMayStopEarly = may_stop_early<Strategy>();
    // A second child of at least this many references is handed out as a task, a range of
    // at least kParallelMin split by the strategy on all of the build's threads.
    static constexpr uint32_t kTaskMin = 4096;
    static constexpr uint32_t kParallelMin = 1u << 16;

    struct Range {
        uint32_t begin, end, depth;
        uint32_t parent;  // appending: node whose second child this range becomes (kInvalidId: none)
        uint32_t pos;     // in place: the node's index
        uint32_t buffer;  // index into buffers
        Bounds3 bounds, centroid_bounds;
    };

    TopDownBuild(const BvhTopDownSettings& settings, const Strategy& prototype, Ref* const* buffers, uint32_t* prim_ids,
                 bool parallel, bool in_place)
        : settings_(settings),
          prototype_(prototype),
          buffers_{buffers[0], buffers[1]},
          prim_ids_(prim_ids),
          parallel_(parallel),
          in_place_(in_place) {}

    // Builds the subtree of `range` into out.piece: appended depth-first, or in place from
    // range.pos.
    void subtree(Range range, Strategy& strategy, EqualCountSplitter<Ref>& equal_counts, TopDownOutput& out) {
        BvhNodeArray& nodes = out.piece.nodes;
        std::vector<Range> pending;  // second children still to build; at most one per level
        for (;;) {
            const uint32_t index = in_place_ ? range.pos : uint32_t(nodes.size());
            if (!in_place_ && range.parent != kInvalidId) nodes[range.parent].index = index;
            const uint32_t count = range.end - range.begin;
            const std::span<Ref> span(buffers_[range.buffer] + range.begin, count);

            // Leaf or split?
            std::optional<BvhSplit> split;
            const bool small = count <= settings_.max_prims;
            if (count > 1 && range.depth < settings_.max_depth && (!small || kMayStopEarly)) {
                const Vec3 extent = range.centroid_bounds.diagonal();
                const int axis = settings_.axis == BvhAxisRule::longest ? max_axis(extent) : int(range.depth % 3);
                const std::span<Ref> span_scratch(buffers_[range.buffer ^ 1] + range.begin, count);
                const bool wide = parallel_ && count >= kParallelMin;
                if (extent[axis] > 0.0f)
                    split = strategy(
                        span, {range.bounds, range.centroid_bounds, axis, range.depth, small, span_scratch, wide});
                if (split && (split->mid == 0 || split->mid >= count))
                    throw std::logic_error("bvh: split strategy returned an empty side");
                if (!split && !small) {
                    ++out.counts.degenerate_splits;
                    const int longest = max_axis(extent);
                    split = equal_counts(span, span_scratch, longest, range.centroid_bounds.lower[longest],
                                         range.centroid_bounds.upper[longest], wide);
                }
            } else if (!small) {
                ++out.counts.forced_leaves;  // at max_depth with more than max_prims primitives
            }

            if (!split) {
                for (uint32_t i = 0; i < count; ++i) prim_ids_[range.begin + i] = span[i].id;
                out.deepest = std::max(out.deepest, range.depth);
                const BvhNode leaf = BvhNode::leaf(range.bounds, range.begin, count);  // kCentroidsOnly: fitted below
                // In place, a forced leaf's subtree is smaller than its 2m - 1 places: the
                // caller sees forced_leaves and builds again, so nothing is written past them.
                if (!in_place_) nodes.push_back(leaf);
                else if (count == 1) nodes[index] = leaf;
                if (pending.empty()) return;
                range = pending.back();
                pending.pop_back();
                continue;
            }
            const uint32_t mid = range.begin + uint32_t(split->mid);
            const uint32_t second_pos = index + 2 * (mid - range.begin);  // in place
            const BvhNode inner = BvhNode::inner(range.bounds, in_place_ ? second_pos : 0, split->axis);
            if (!in_place_) nodes.push_back(inner);  // second child patched later
            else nodes[index] = inner;
            const uint32_t buffer = range.buffer ^ uint32_t(split->in_scratch);
            Range first{range.begin, mid, range.depth + 1, kInvalidId, index + 1, buffer, {}, {}};
            Range second{mid, range.end, range.depth + 1, index, second_pos, buffer, {}, {}};
            if (split->fitted) {
                first.bounds = split->bounds[0];
                first.centroid_bounds = split->centroid_bounds[0];
                second.bounds = split->bounds[1];
                second.centroid_bounds = split->centroid_bounds[1];
            } else {
                fit(std::span<const Ref>(buffers_[buffer] + first.begin, first.end - first.begin), first.bounds,
                    first.centroid_bounds);
                fit(std::span<const Ref>(buffers_[buffer] + second.begin, second.end - second.begin), second.bounds,
                    second.centroid_bounds);
            }
            if (parallel_ && second.end - second.begin >= kTaskMin) {
                hand_out(first, second, index, strategy, equal_counts, out);
                if (pending.empty()) return;
                range = pending.back();
                pending.pop_back();
                continue;
            }
            pending.push_back(second);
            range = first;
        }
    }

private:
    // Builds `first` on this task and `second` on another, with a strategy and fallback of its
    // own; appending, into a piece of its own, which goes in after the first child's subtree
    // (its root is index 0 of the piece, relocated on assembly).
    void hand_out(Range first, Range second, uint32_t parent, Strategy& strategy, EqualCountSplitter<Ref>& equal_counts,
                  TopDownOutput& out) {
        std::unique_ptr<BvhPiece> piece;
        if (!in_place_) {
            piece = std::make_unique<BvhPiece>();
            second.parent = kInvalidId;
        }
        TopDownOutput task{in_place_ ? out.piece : *piece, {}, 0};
        fork_join(
            true, [&] { subtree(first, strategy, equal_counts, out); },
            [&] {
                Strategy own = prototype_;
                EqualCountSplitter<Ref> own_equal_counts;
                subtree(second, own, own_equal_counts, task);
            });
        if (!in_place_) out.piece.add_hole(parent, std::move(piece));
        out.counts.degenerate_splits += task.counts.degenerate_splits;
        out.counts.forced_leaves += task.counts.forced_leaves;
        out.deepest = std::max(out.deepest, task.deepest);
    }

    const BvhTopDownSettings& settings_;
    const Strategy& prototype_;  // as it was before the build: each task copies it
    Ref* const buffers_[2];
    uint32_t* const prim_ids_;
    const bool parallel_, in_place_;
};

}  // namespace detail

// The build. On one thread, the nodes are appended depth-first by one loop. On several
// (settings.parallel, inside a BuildThreads::run), a second child of kTaskMin references or
// more is handed out as a task, and the strategy splits ranges of kParallelMin or more on all
// of the build's threads. Where a task's nodes go: with max_prims 1 every leaf holds one
// primitive and a subtree over m of them has exactly 2m - 1 nodes, so each task writes in
// place into the final array, sized 2n - 1 beforehand (a leaf forced at max_depth breaks
// that; the build then starts again appending); otherwise into a piece of its own, the
// pieces assembled depth-first at the end (base/tree_pieces.h). The array is the one thread's
// either way, and the strategies' parallel splits give their serial answers (base/parallel.h).
template <BvhSplitStrategy Strategy>
FlatBvh build_bvh_top_down(const Scene& scene, const BvhTopDownSettings& settings, Strategy& strategy,
                           BvhTopDownCounts& counts) {
    using Build = detail::TopDownBuild<Strategy>;
    using Ref = typename Build::Ref;
    constexpr bool kCentroidsOnly = std::is_same_v<Ref, BvhCentroidRef>;  // node boxes made bottom-up
    if (scene.triangle_count() > BvhNode::kMaxLeafPrims)
        throw std::runtime_error("bvh: scene '" + scene.name + "' has more triangles than a BVH node can count");
    FlatBvh bvh;
    counts = {};
    const uint32_t n = uint32_t(scene.triangle_count());
    const bool parallel = settings.parallel;
    const detail::RefBuffer<Ref> refs(n), scratch(n);
    if (n == 0) {
        bvh.finalize(scene);
        return bvh;
    }
    // A range's references are in one of two buffers: a strategy that partitions out of
    // place leaves its children in the other one (BvhSplit::in_scratch), which is then
    // their scratch, so nothing is copied back.
    Ref* const buffers[2] = {refs.data(), scratch.data()};
    bvh.prim_ids.resize(n);
    const Strategy prototype = strategy;  // before it is used: what each task starts from

    auto attempt = [&](bool in_place) {
        put_refs(scene, refs.data(), parallel);
        typename Build::Range root{0, n, 0, kInvalidId, 0, 0, {}, {}};
        detail::fit_parallel<Ref>(std::span<const Ref>(refs.data(), n), root.bounds, root.centroid_bounds, parallel);
        BvhPiece piece;
        // A binary tree with non-empty leaves has at most 2n-1 nodes.
        if (in_place) piece.nodes.resize(2 * size_t(n) - 1);  // not written (DefaultInitAllocator)
        else if (!parallel) piece.nodes.reserve(2 * size_t(n) - 1);
        detail::TopDownOutput out{piece, {}, 0};
        detail::EqualCountSplitter<Ref> equal_counts;  // the fallback for ranges the strategy cannot separate
        Build(settings, prototype, buffers, bvh.prim_ids.data(), parallel, in_place)
            .subtree(root, strategy, equal_counts, out);
        counts = out.counts;
        if (in_place && counts.forced_leaves > 0) return std::optional<uint32_t>();
        assemble_bvh_pieces(piece, bvh.nodes, parallel);
        bvh.nodes.shrink_to_fit();  // leaves of several primitives leave part of the 2n-1 unused
        return std::optional<uint32_t>(out.deepest);
    };
    std::optional<uint32_t> deepest = attempt(parallel && settings.max_prims == 1);
    if (!deepest) {
        strategy = prototype;
        deepest = attempt(false);
    }
    bvh.finalize(scene, *deepest, parallel);
    if constexpr (kCentroidsOnly) detail::fit_bottom_up(bvh, parallel);
    return bvh;
}

}  // namespace accelbench
