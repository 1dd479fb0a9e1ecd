// The kd-tree's build (report 4.1.2; pbrt-v3's KdTreeAccel::buildTree; Wald & Havran 2006
// for the nlogn event lists): the SAH sweep over edge events, the classification of
// primitives, and the top-down recursion both builders share.
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "accelbench/accel/kdtree/kdtree.h"
#include "accelbench/base/parallel.h"
#include "accelbench/base/radix_sort.h"
#include "accelbench/base/tree_pieces.h"

namespace accelbench {

// ---- build ------------------------------------------------------------------------
//
// Candidate planes are the faces of the primitives' bounding boxes (report Figure 14),
// as events along each axis. A primitive with extent on the axis has a start event at
// its lower face and an end event at its upper face; a primitive flat on the axis has a
// single planar event (Wald & Havran 2006, section 4.2). At one plane position t:
//   - a primitive ending at t (upper == t, lower < t) lies below the plane only;
//   - a primitive starting at t (lower == t, upper > t) lies above only;
//   - a primitive lying IN the plane (lower == upper == t) goes to the side whose SAH
//     cost is lower (ties: below). Either side is correct for traversal: the plane is a
//     face of both children, and a ray hitting the primitive there crosses that face,
//     so it visits whichever child holds the primitive (unless a closer hit ends it).
//   - everything with lower < t < upper goes to both children.
// pbrt instead evaluates one candidate per edge with starts sorted before ends, which
// sends primitives merely touching the plane to both sides; grouping all events at one
// position makes the counts exact and the choice independent of how equal positions
// happened to be ordered, which is what lets both builders agree bit for bit.

namespace {

// Event order at one position: ends, then planar, then starts, so a sweep sees at t
// first what leaves the above side, then what lies in the plane, then what enters.
enum EventType : uint32_t { kEnd = 0, kPlanar = 1, kStart = 2 };

// An event is one 64-bit key that sorts by (position, type, primitive): the position's
// bits mapped so that unsigned order is float order, then 2 type bits, then 30 bits of
// primitive index. Sorting plain integers is fast and makes the order total.
using EventKey = uint64_t;
constexpr uint32_t kPrimBits = 30;
constexpr uint32_t kPrimMask = (1u << kPrimBits) - 1;

uint32_t ordered_bits(float f) {
    // +0.0f turns -0.0f into +0.0f, so equal positions have equal keys.
    const uint32_t b = std::bit_cast<uint32_t>(f + 0.0f);
    return (b & 0x80000000u) ? ~b : (b | 0x80000000u);
}
float position_of_bits(uint32_t k) { return std::bit_cast<float>((k & 0x80000000u) ? (k & 0x7fffffffu) : ~k); }
EventKey make_event(float t, EventType type, uint32_t prim) {
    return (EventKey(ordered_bits(t)) << 32) | (uint32_t(type) << kPrimBits) | prim;
}
uint32_t position_bits(EventKey e) { return uint32_t(e >> 32); }
EventType type_of(EventKey e) { return EventType((uint32_t(e) >> kPrimBits) & 3u); }
uint32_t prim_of(EventKey e) { return uint32_t(e) & kPrimMask; }

// Appends the one or two events of primitive `prim` on `axis` at out[n...]; returns the new n.
size_t put_events(EventKey* out, size_t n, const Bounds3& b, int axis, uint32_t prim) {
    if (b.lower[axis] == b.upper[axis]) {
        out[n++] = make_event(b.lower[axis], kPlanar, prim);
    } else {
        out[n++] = make_event(b.lower[axis], kStart, prim);
        out[n++] = make_event(b.upper[axis], kEnd, prim);
    }
    return n;
}

// Which children a primitive goes to: bit 0 below, bit 1 above.
constexpr uint8_t kBelow = 1, kAbove = 2, kBoth = 3;

// Below when it starts before t, above when it ends after t, both when both; neither
// only when it lies in the plane (lo == hi == t), which goes to planar_below's side.
// Without branches: which case a primitive is in is as unpredictable as the scene
// (1.06M mispredictions of the bunny's build when branched).
uint8_t classify(const Bounds3& b, int axis, float t, bool planar_below) {
    const float lo = b.lower[axis], hi = b.upper[axis];
    const uint8_t side = uint8_t(uint8_t(lo < t) | uint8_t(hi > t) << 1);
    return side | uint8_t(side == 0) * (planar_below ? kBelow : kAbove);
}

struct Split {
    int axis = -1;
    float position = 0.0f;
    bool planar_below = true;
    float cost = kInfinity;
};

struct SahConstants {
    float traversal, isect, empty_bonus;

    // pbrt-v3: C_T + C_I (1 - b_e) (p_B N_B + p_A N_A), b_e only when a side is empty.
    float split_cost(float p_below, float p_above, uint32_t n_below, uint32_t n_above) const {
        const float bonus = (n_below == 0 || n_above == 0) ? empty_bonus : 0.0f;
        return traversal + isect * (1.0f - bonus) * (p_below * float(n_below) + p_above * float(n_above));
    }
};

// The SAH sweep over one axis: `events` are the sorted events of the node's n primitives
// (including parts outside the node, which only shift the counts); every distinct
// position strictly inside the node is a candidate. Updates `best` when a candidate is
// strictly cheaper, so among equal costs the first axis tried and the lowest position win.
// One price per group of equal positions: pricing every event to drop the group loop's
// mispredictions cost more instructions than it saved (docs/decisions.md, kd-tree).
void sweep_axis(std::span<const EventKey> events, int axis, const Bounds3& node, uint32_t n, const SahConstants& k,
                Split& best) {
    const float lo = node.lower[axis], hi = node.upper[axis];
    if (!(lo < hi)) return;
    const Vec3 d = node.diagonal();
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    const float cap = d[a1] * d[a2], rim = d[a1] + d[a2];
    const float inv_area = 1.0f / node.area();
    // The list is sorted, so the events outside the node (28% of those the bunny's build
    // sweeps: primitives straddling an ancestor's plane) are a prefix (at or below lo)
    // and a suffix (at or above hi). The prefix only shifts the counts, one event at a
    // time without a branch on its type: an end leaves the above side, a start joins the
    // below side, a planar event does both. The suffix follows the last candidate and is
    // not read. Testing every group for lying inside the node instead cost a
    // misprediction at each boundary and a pass over the suffix.
    const uint32_t lo_key = ordered_bits(lo), hi_key = ordered_bits(hi);  // float order, -0 as +0
    const EventKey* ev = events.data();
    const size_t m = events.size();
    uint32_t n_below = 0, n_above = n;
    size_t i = 0;
    for (; i < m && position_bits(ev[i]) <= lo_key; ++i) {
        const EventType type = type_of(ev[i]);
        n_above -= type != kStart;
        n_below += type != kEnd;
    }
    while (i < m) {
        const uint32_t key = position_bits(ev[i]);
        if (key >= hi_key) break;
        uint32_t counts[3] = {0, 0, 0};  // by EventType
        for (; i < m && position_bits(ev[i]) == key; ++i) ++counts[type_of(ev[i])];
        const uint32_t planar = counts[kPlanar];
        n_above -= counts[kEnd] + planar;
        const float t = position_of_bits(key);
        const float p_below = 2.0f * (cap + (t - lo) * rim) * inv_area;
        const float p_above = 2.0f * (cap + (hi - t) * rim) * inv_area;
        const float c_below = k.split_cost(p_below, p_above, n_below + planar, n_above);
        const float c_above = planar ? k.split_cost(p_below, p_above, n_below, n_above + planar) : c_below;
        const bool planar_below = c_below <= c_above;
        const float c = planar_below ? c_below : c_above;
        if (c < best.cost) best = {axis, t, planar_below, c};
        n_below += counts[kStart] + planar;
    }
}

struct BuildCounters {
    uint64_t bad_refines = 0;  // splits made although they cost more than a leaf
};

[[noreturn]] void throw_limit(uint64_t limit, const char* what) {
    throw std::runtime_error("kdtree: build exceeds its limit of " + std::to_string(limit) + " " + what +
                             " (references: " + std::to_string(KdTree::kMaxRefsPerPrim) + " per triangle, at least " +
                             std::to_string(KdTree::kMinRefBudget) +
                             "; nodes and references: 2^30 - 1); lower max_depth or raise max_prims or "
                             "traversal_cost");
}

// A stack of lists that grows without initialising what it hands out (the builder
// writes every element it claims) and is cut back with truncate().
template <class T>
class ListStack {
public:
    size_t size() const { return size_; }
    T* data() { return data_.get(); }
    const T* data() const { return data_.get(); }
    T* grow(size_t n) {  // n more elements at the top
        if (size_ + n > capacity_) reserve(std::max(size_ + n, 2 * capacity_));
        size_ += n;
        return data_.get() + size_ - n;
    }
    void reserve(size_t cap) {
        if (cap <= capacity_) return;
        auto bigger = std::make_unique_for_overwrite<T[]>(cap);
        std::copy(data_.get(), data_.get() + size_, bigger.get());
        data_ = std::move(bigger);
        capacity_ = cap;
    }
    void truncate(size_t n) { size_ = n; }

private:
    std::unique_ptr<T[]> data_;
    size_t size_ = 0, capacity_ = 0;
};

// What every task of one build shares: the scene's boxes and the settings, the count of
// primitive references made so far (the memory bound), and the side array of each thread.
class BuildShared {
public:
    BuildShared(const Scene& scene, const KdTree::Config& s, int max_depth, bool parallel)
        : bounds(scene.prim_bounds),
          sah{s.traversal_cost, s.isect_cost, s.empty_bonus},
          max_prims(uint32_t(s.max_prims)),
          max_depth(max_depth),
          presorted(s.build == KdTree::BuildAlgorithm::NLogN),
          ref_budget(s.max_refs
                         ? *s.max_refs
                         : std::max<uint64_t>(KdTree::kMinRefBudget, KdTree::kMaxRefsPerPrim * scene.triangle_count())),
          parallel(parallel),
          task_min(std::max<size_t>(
              kMinTask, scene.triangle_count() / (kTasksPerThread * size_t(tbb::this_task_arena::max_concurrency())))),
          sides_(parallel ? size_t(tbb::this_task_arena::max_concurrency()) : 1) {}

    const std::vector<Bounds3>& bounds;
    const SahConstants sah;
    const uint32_t max_prims;
    const int max_depth;
    const bool presorted;
    const uint64_t ref_budget;
    const bool parallel;
    // An above child of at least this many primitives is handed out as a task (several
    // threads): its lists are copied, so only near the top, about kTasksPerThread subtrees
    // of the root's size per thread (which subtrees go to tasks changes nothing in the
    // tree). Dragon, 2 threads, median of 5 builds (one thread: 925 ms): root / 32 (this)
    // 540 ms, root / 128 536 ms; every above child of 4096 or more 558 ms (accel_bench).
    static constexpr size_t kMinTask = 4096, kTasksPerThread = 16;
    const size_t task_min;
    std::atomic<uint64_t> refs{0};  // references made (the root's, then each split's copies)

    // The side of each primitive for the node being split on this thread. A thread writes it
    // (classify) and reads it (split_list) within one node, with no wait for other tasks in
    // between, so one array per thread serves every task that thread runs.
    uint8_t* side() {
        std::vector<uint8_t>& s = sides_[parallel ? size_t(tbb::this_task_arena::current_thread_index()) : 0];
        if (s.size() != bounds.size()) s.assign(bounds.size(), 0);
        return s.data();
    }

private:
    std::vector<std::vector<uint8_t>> sides_;
};

// The top-down recursion shared by both algorithms. A node's lists live in stacks: its
// primitive list (ascending indices, in both builds) and, for nlogn, its three sorted
// event lists. Splitting a node appends the above child's lists on top of each stack and
// compacts the below child's lists in place over the parent's (a stable filter, so
// order is kept); the below subtree is built, the stacks are cut back, then the above
// subtree is built. Memory is the current path plus the pending above-siblings.
//
// On several threads (base/parallel.h) a large above child (BuildShared::task_min) is
// handed out as a task: its lists are copied into the stacks of a builder of its own, which
// writes the subtree into a piece (base/tree_pieces.h) that goes where the one-thread build
// puts that subtree, right after the below child's. The tree is the one thread's: each
// node's split depends on its lists alone.
class Builder {
public:
    using Piece = TreePiece<KdNode, uint32_t>;

    // Writes into nodes and prim_indices; `piece`, when given, is what they belong to (on
    // several threads: where handed-out subtrees are recorded).
    Builder(BuildShared& shared, std::vector<KdNode>& nodes, std::vector<uint32_t>& prim_indices, Piece* piece)
        : shared_(shared), nodes_(nodes), prim_indices_(prim_indices), piece_(piece) {}

    void run(const Bounds3& root) {
        const uint32_t n = uint32_t(shared_.bounds.size());
        const bool parallel = shared_.parallel;
        Lists lists;
        // The stacks start at the size they reach (the bunny's and the conference's lists
        // peak at 4x the root's): memory not yet used is not touched, so reserving it costs
        // no page faults, and each regrowth it saves copied the stack into fresh pages (the
        // dragon's build: a third fewer minor faults; docs/decisions.md, kd-tree).
        prims_.reserve(4 * size_t(n));
        for (ListStack<EventKey>& events : events_) events.reserve(8 * size_t(n));
        uint32_t* prims = prims_.grow(n);
        for_blocks(parallel, n, kBlock, [&](size_t, size_t begin, size_t end) {
            for (size_t i = begin; i < end; ++i) prims[i] = uint32_t(i);
        });
        lists.prims = {0, n};
        shared_.refs = n;
        if (shared_.presorted) {
            for (int axis = 0; axis < 3; ++axis) {
                const size_t m = root_events(axis, events_[axis].grow(2 * size_t(n)));
                events_[axis].truncate(m);
                sort_root_events(events_[axis].data(), m);
                lists.events[axis] = {0, m};
            }
            std::vector<EventKey>().swap(scratch_);  // nlogn needs no scratch below the root
        }
        build_node(root, lists, 0, 0);
        publish_refs();
    }

    const BuildCounters& counters() const { return counters_; }
    int deepest_leaf() const { return deepest_leaf_; }

private:
    struct Range {
        size_t begin = 0, end = 0;
        size_t size() const { return end - begin; }
    };
    struct Lists {
        Range prims;
        Range events[3];  // nlogn only
    };
    static constexpr size_t kBlock = 1 << 14;  // primitives per block of the root's parallel loops

    static void sort_events(EventKey* ev, size_t m) { std::sort(ev, ev + m); }

    // The root's events on one axis into ev, in ascending primitive order; returns how many.
    // On several threads in blocks, each written from where the blocks before it end.
    size_t root_events(int axis, EventKey* ev) const {
        const std::vector<Bounds3>& bounds = shared_.bounds;
        const size_t n = bounds.size();
        if (!shared_.parallel) {
            size_t m = 0;
            for (uint32_t p = 0; p < n; ++p) m = put_events(ev, m, bounds[p], axis, p);
            return m;
        }
        std::vector<size_t> start(block_count(n, kBlock) + 1, 0);
        for_blocks(true, n, kBlock, [&](size_t k, size_t begin, size_t end) {
            size_t m = 0;
            for (size_t p = begin; p < end; ++p) m += bounds[p].lower[axis] == bounds[p].upper[axis] ? 1 : 2;
            start[k + 1] = m;
        });
        for (size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
        for_blocks(true, n, kBlock, [&](size_t k, size_t begin, size_t end) {
            size_t m = start[k];
            for (size_t p = begin; p < end; ++p) m = put_events(ev, m, bounds[p], axis, uint32_t(p));
        });
        return start.back();
    }

    // The root's events on one axis, the largest sort of the nlogn build: a radix sort
    // (base/radix_sort.h) on the position and type bits of the key only. The events were
    // made in ascending primitive order and each pass is stable, so events of equal
    // position and type keep that order, which is the order of the whole key (primitive
    // index included) that sort_events gives: the same list, the same tree. std::sort's
    // comparisons of positions branch as unpredictably as the scene: 2.5M of the bunny
    // build's 8.8M mispredicted branches (callgrind --branch-sim) were this sort.
    void sort_root_events(EventKey* ev, size_t m) {
        scratch_.resize(m);
        radix_sort(
            std::span<EventKey>(ev, m), std::span<EventKey>(scratch_), int(64 - kPrimBits), kRootSortDigitBits,
            [](EventKey e) { return e >> kPrimBits; }, shared_.parallel);
    }
    // 34 key bits in 3 passes of 12-bit digits (4096 buckets).
    static constexpr int kRootSortDigitBits = 12;

    // The node's sorted events on `axis`: a slice of the presorted lists (nlogn), or
    // generated from the primitive list and sorted here (pbrt).
    std::span<const EventKey> events_of(const Lists& lists, int axis) {
        if (shared_.presorted) return {events_[axis].data() + lists.events[axis].begin, lists.events[axis].size()};
        scratch_.resize(2 * lists.prims.size());
        EventKey* ev = scratch_.data();
        const uint32_t* prims = prims_.data();
        size_t m = 0;
        for (size_t i = lists.prims.begin; i < lists.prims.end; ++i)
            m = put_events(ev, m, shared_.bounds[prims[i]], axis, prims[i]);
        sort_events(ev, m);
        return {ev, m};
    }

    // Longest axis first; the other axes only when it offers no split cheaper than a
    // leaf (the report's "try other axes instead"), keeping the cheapest seen. pbrt-v3
    // retries only when an axis has no candidate at all; retrying also after a bad
    // candidate turns some of its bad refines into good splits.
    Split choose_split(const Bounds3& node, const Lists& lists, float leaf_cost) {
        Split best;
        if (!(node.area() > 0.0f)) return best;
        const int first = node.largest_axis();
        for (int k = 0; k < 3; ++k) {
            const int axis = (first + k) % 3;
            sweep_axis(events_of(lists, axis), axis, node, uint32_t(lists.prims.size()), shared_.sah, best);
            if (best.axis >= 0 && best.cost < leaf_cost) break;
        }
        return best;
    }

    void make_leaf(uint32_t index, Range prims, int depth) {
        const uint32_t count = uint32_t(prims.size());
        const uint32_t* p = prims_.data() + prims.begin;
        if (count <= 1) {
            // An empty leaf has no run: offset 0, so that its node does not depend on the
            // references placed before it (which a task building a piece cannot know).
            nodes_[index] = KdNode::leaf(count, count ? p[0] : 0);
        } else {
            check_limit(prim_indices_.size() + count, KdNode::kMaxIndex, "primitive references");
            nodes_[index] = KdNode::leaf(count, uint32_t(prim_indices_.size()));
            prim_indices_.insert(prim_indices_.end(), p, p + count);
        }
        deepest_leaf_ = std::max(deepest_leaf_, depth);
    }

    // The references a split copied (to both children) count against the budget; they are
    // added to the shared count in batches, and the build stops once that count is over it.
    // References are only ever added, so whether a build stops does not depend on when the
    // batches arrive.
    void add_refs(uint64_t copies) {
        unpublished_refs_ += copies;
        if (unpublished_refs_ >= kRefBatch) publish_refs();
    }
    void publish_refs() {
        const uint64_t total = shared_.refs.fetch_add(unpublished_refs_) + unpublished_refs_;
        unpublished_refs_ = 0;
        check_limit(total, shared_.ref_budget, "primitive references");
    }
    static constexpr uint64_t kRefBatch = 4096;

    void check_limit(uint64_t value, uint64_t limit, const char* what) const {
        if (value > limit) throw_limit(limit, what);
    }

    // Splits one list (a range of `stack`) by `side`: the above part is appended at the
    // top, the below part compacted in place. Returns {below, above}. One pass, written
    // without branches on the side, which is as unpredictable as the scene: every element
    // is stored to both outputs and each output's end advances only when the element
    // belongs there (below is compacted in place: its write index never passes the read
    // index). `keep` masks the sides wanted (kBelow, kAbove or kBoth): a child that will
    // be a leaf needs no event lists, so its part is not kept (a side not kept comes back
    // empty). (Two passes, one per side, read each element and its side twice: 464M
    // instructions of the bunny's 1.12G build against 380M for this one.) Splitting the
    // sorted lists costs less than sorting even a small node's events (docs/decisions.md,
    // kd-tree).
    template <class T, class PrimOf>
    static std::pair<Range, Range> split_list(ListStack<T>& stack, Range r, const uint8_t* side, PrimOf prim,
                                              uint8_t keep = kBoth) {
        const size_t above_begin = stack.size();
        T* above = stack.grow(r.size());
        T* list = stack.data() + r.begin;  // after grow(): it may move the stack
        size_t n_above = 0, n_below = 0;
        for (size_t i = 0; i < r.size(); ++i) {
            const T e = list[i];
            const uint32_t s = side[prim(e)] & keep;
            above[n_above] = e;
            list[n_below] = e;
            n_above += s >> 1;
            n_below += s & kBelow;
        }
        stack.truncate(above_begin + n_above);
        return {{r.begin, r.begin + n_below}, {above_begin, above_begin + n_above}};
    }

    // A node of n primitives at `depth` is a leaf whatever the SAH says: few enough
    // primitives, or the depth limit (pbrt's first termination test).
    bool leaf_by_limits(size_t n, int depth) const { return n <= shared_.max_prims || depth >= shared_.max_depth; }

    void build_node(const Bounds3& node, const Lists& lists, int depth, int bad_refines) {
        check_limit(nodes_.size() + 1, KdNode::kMaxIndex, "nodes");
        const uint32_t index = uint32_t(nodes_.size());
        nodes_.emplace_back();
        const uint32_t n = uint32_t(lists.prims.size());
        if (leaf_by_limits(n, depth)) return make_leaf(index, lists.prims, depth);

        const float leaf_cost = shared_.sah.isect * float(n);
        const Split split = choose_split(node, lists, leaf_cost);
        // pbrt's termination: a split dearer than the leaf is tolerated three times on a
        // path (it may enable cheap splits below), one much dearer only for big nodes.
        const bool bad = split.axis >= 0 && split.cost > leaf_cost;
        if (bad) ++bad_refines;
        if (split.axis < 0 || (split.cost > 4.0f * leaf_cost && n < 16) || bad_refines == 3)
            return make_leaf(index, lists.prims, depth);
        counters_.bad_refines += bad;

        uint8_t* const side = shared_.side();
        const uint32_t* prims = prims_.data();
        for (size_t i = lists.prims.begin; i < lists.prims.end; ++i)
            side[prims[i]] = classify(shared_.bounds[prims[i]], split.axis, split.position, split.planar_below);
        Lists below, above;
        std::tie(below.prims, above.prims) = split_list(prims_, lists.prims, side, [](uint32_t p) { return p; });
        if (shared_.presorted) {
            // Only a child that will be split needs its sorted events (a leaf reads its
            // primitive list alone); at the last level neither does.
            const auto splits = [&](Range r) { return !leaf_by_limits(r.size(), depth + 1); };
            const uint8_t keep = uint8_t((splits(below.prims) ? kBelow : 0) | (splits(above.prims) ? kAbove : 0));
            if (keep)
                for (int axis = 0; axis < 3; ++axis)
                    std::tie(below.events[axis], above.events[axis]) = split_list(
                        events_[axis], lists.events[axis], side, [](EventKey e) { return prim_of(e); }, keep);
        }
        add_refs(below.prims.size() + above.prims.size() - n);

        Bounds3 below_bounds = node, above_bounds = node;
        below_bounds.upper[split.axis] = above_bounds.lower[split.axis] = split.position;
        if (shared_.parallel && above.prims.size() >= shared_.task_min) {
            nodes_[index] = KdNode::interior(split.axis, split.position, 0);  // the hole's root
            return hand_out(index, below_bounds, below, above_bounds, above, depth, bad_refines);
        }
        const size_t saved_prims = prims_.size();
        size_t saved_events[3];
        for (int axis = 0; axis < 3; ++axis) saved_events[axis] = events_[axis].size();

        build_node(below_bounds, below, depth + 1, bad_refines);
        prims_.truncate(saved_prims);
        for (int axis = 0; axis < 3; ++axis) events_[axis].truncate(saved_events[axis]);
        nodes_[index] = KdNode::interior(split.axis, split.position, uint32_t(nodes_.size()));
        build_node(above_bounds, above, depth + 1, bad_refines);
    }

    // Builds the below child here and the above child (whose lists are on top of the stacks)
    // on another task, with its lists moved to a builder of its own, into a piece recorded
    // as a hole after the below child's subtree; node `index` refers to its root.
    void hand_out(uint32_t index, const Bounds3& below_bounds, const Lists& below, const Bounds3& above_bounds,
                  const Lists& above, int depth, int bad_refines) {
        auto piece = std::make_unique<Piece>();
        Builder other(shared_, piece->nodes, piece->items, piece.get());
        Lists theirs;
        theirs.prims = other.adopt(other.prims_, prims_, above.prims);
        prims_.truncate(above.prims.begin);
        if (shared_.presorted)
            for (int axis = 0; axis < 3; ++axis) {
                theirs.events[axis] = other.adopt(other.events_[axis], events_[axis], above.events[axis]);
                // An above child that was not kept has an empty range at the top.
                if (above.events[axis].size()) events_[axis].truncate(above.events[axis].begin);
            }
        fork_join(
            true, [&] { build_node(below_bounds, below, depth + 1, bad_refines); },
            [&] {
                other.build_node(above_bounds, theirs, depth + 1, bad_refines);
                other.publish_refs();
            });
        piece_->add_hole(index, std::move(piece));
        counters_.bad_refines += other.counters_.bad_refines;
        deepest_leaf_ = std::max(deepest_leaf_, other.deepest_leaf_);
    }

    // Copies a list of another builder's stack onto this one's (reserved as the one-thread
    // build reserves its root's), returning where it lies.
    template <class T>
    static Range adopt(ListStack<T>& mine, const ListStack<T>& from, Range r) {
        mine.reserve(4 * r.size());  // the root's: 4n primitives, 8n events (2n in its lists)
        T* out = mine.grow(r.size());
        std::copy(from.data() + r.begin, from.data() + r.end, out);
        return {0, r.size()};
    }

    BuildShared& shared_;
    std::vector<KdNode>& nodes_;
    std::vector<uint32_t>& prim_indices_;
    Piece* piece_;                   // what nodes_ and prim_indices_ belong to (several threads)
    ListStack<uint32_t> prims_;      // primitive lists
    ListStack<EventKey> events_[3];  // nlogn: sorted event lists per axis
    std::vector<EventKey> scratch_;  // one node's events on one axis, sorted on the spot
    BuildCounters counters_;
    uint64_t unpublished_refs_ = 0;  // copies made by splits, not yet added to shared_.refs
    int deepest_leaf_ = 0;
};

}  // namespace

void KdTree::build(const Scene& scene) {
    threads_.run([&] { build_on_threads(scene); });
}

void KdTree::build_on_threads(const Scene& scene) {
    const size_t n = scene.triangle_count();
    if (n > kPrimMask)
        throw std::runtime_error("kdtree: scene '" + scene.name + "' has " + std::to_string(n) +
                                 " triangles; at most 2^30 - 1 are supported");
    if (scene.prim_bounds.size() != n) throw std::runtime_error("kdtree: scene '" + scene.name + "' is not finalized");
    const bool parallel = threads_.parallel();
    corners_.resize(n);
    for_blocks(parallel, n, 1 << 14, [&](size_t, size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i)
            corners_[i] = {scene.vertex(uint32_t(i), 0), scene.vertex(uint32_t(i), 1), scene.vertex(uint32_t(i), 2)};
    });
    bounds_ = scene.bounds;
    nodes_.clear();
    prim_indices_.clear();
    max_depth_used_ = config_.max_depth ? *config_.max_depth : default_max_depth(n);
    // Only a scene of more than 2^92 triangles would get a default above the limit.
    max_depth_used_ = std::min(max_depth_used_, kMaxDepthLimit);

    BuildCounters counters;
    int deepest = 0;
    if (n > 0) {
        try {
            BuildShared shared(scene, config_, max_depth_used_, parallel);
            // On several threads the root's own nodes go to a piece like every task's; one
            // without holes is the tree as it is.
            Builder::Piece root;
            if (parallel) {
                root.nodes.swap(nodes_);
                root.items.swap(prim_indices_);
            }
            Builder builder(shared, parallel ? root.nodes : nodes_, parallel ? root.items : prim_indices_,
                            parallel ? &root : nullptr);
            builder.run(bounds_);
            counters = builder.counters();
            deepest = builder.deepest_leaf();
            if (parallel && root.holes.empty()) {
                nodes_.swap(root.nodes);
                prim_indices_.swap(root.items);
            } else if (parallel) {
                const auto [nodes, items] = root.layout();
                if (nodes > KdNode::kMaxIndex) throw_limit(KdNode::kMaxIndex, "nodes");
                if (items > KdNode::kMaxIndex) throw_limit(KdNode::kMaxIndex, "primitive references");
                nodes_.resize(nodes);
                prim_indices_.resize(items);
                root.assemble(nodes_.data(), prim_indices_.data(), true,
                              [](KdNode& node, const Builder::Piece::Map& own, const Builder::Piece::Map& refs) {
                                  if (!node.is_leaf())
                                      node = KdNode::interior(node.axis(), node.split(),
                                                              uint32_t(refs.node(node.above_child())));
                                  else if (node.prim_count() > 1)
                                      node = KdNode::leaf(node.prim_count(), uint32_t(own.item(node.prim_offset())));
                              });
            }
        } catch (...) {
            // A build that stopped at a limit leaves no half tree behind: an empty tree
            // answers every ray with a miss, never with a wrong hit.
            nodes_ = {};
            prim_indices_ = {};
            throw;
        }
    }
    nodes_.shrink_to_fit();
    prim_indices_.shrink_to_fit();
    bad_refines_ = counters.bad_refines;
    deepest_leaf_ = deepest;
}

}  // namespace accelbench
