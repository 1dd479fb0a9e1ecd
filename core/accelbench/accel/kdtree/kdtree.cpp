#include "accelbench/accel/kdtree/kdtree.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "accelbench/accel/tree_tally.h"
#include "accelbench/base/param_table.h"
#include "accelbench/base/radix_sort.h"
#include "accelbench/base/triangle.h"

namespace accelbench {

namespace {

// The parameters, each once: its row and its Config member, whose initializer is the default.
const ParamTable<KdTree::Config>& kdtree_params() {
    using C = KdTree::Config;
    static const ParamTable<C> rows = {
        enum_param("build", &C::build, KdTree::kBuildNames,
                   "nlogn: events sorted once, split in linear time (Wald & Havran 2006); pbrt: edges sorted at "
                   "every node. Both give the same tree"),
        float_param("isect_cost", &C::isect_cost, 1e-4, 1e4, "SAH cost of one ray/triangle test C_I"),
        float_param("traversal_cost", &C::traversal_cost, 1e-4, 1e4, "SAH cost of one traversal step C_T"),
        float_param("empty_bonus", &C::empty_bonus, 0, 1, "b_e: fraction of the cost forgiven when one child is empty"),
        int_param("max_prims", &C::max_prims, 0, KdNode::kMaxIndex,
                  "nodes with at most this many primitives become leaves"),
        auto_int_param("max_depth", &C::max_depth, 0, KdTree::kMaxDepthLimit,
                       "deepest level; auto = round(8 + 1.3 log2 N)"),
        bool_param("mailbox", &C::mailbox,
                   "test a triangle once per ray even when several leaves the ray visits hold it (the same "
                   "answers; prim_tests then counts the tests made)"),
    };
    return rows;
}

}  // namespace

AcceleratorInfo KdTree::info() {
    return {.name = "kdtree",
            .description =
                "SAH kd-tree after pbrt-v3 (report section 4): 8-byte nodes, edge-event SAH, front-to-back traversal",
            .params = kdtree_params().specs(),
            .create = [](const ParamSet& p) { return std::make_unique<KdTree>(p); },
            .label = fixed_label("kd-tree"),
            // A given max_depth; the default's depends on the scene.
            .depth_limit = [](const ParamSet& p) -> std::optional<uint64_t> {
                const std::optional<int> depth = Config::from(p).max_depth;
                return depth ? std::optional<uint64_t>(uint64_t(*depth)) : std::nullopt;
            }};
}

KdTree::Config KdTree::Config::from(const ParamSet& p) { return kdtree_params().from(p); }

KdTree::KdTree(const ParamSet& params) : KdTree(Config::from(params)) {}

KdTree::KdTree(const Config& config) : config_(config) {
    if (config_.max_depth && (*config_.max_depth < 0 || *config_.max_depth > kMaxDepthLimit))
        throw std::invalid_argument("kdtree: max_depth " + std::to_string(*config_.max_depth) + " is outside [0, " +
                                    std::to_string(kMaxDepthLimit) + "]");
    if (config_.max_prims < 0) throw std::invalid_argument("kdtree: max_prims must be >= 0");
    if (!(config_.isect_cost > 0) || !(config_.traversal_cost > 0) || !(config_.empty_bonus >= 0) ||
        !(config_.empty_bonus <= 1))
        throw std::invalid_argument("kdtree: costs must be > 0 and empty_bonus in [0, 1]");
}

int KdTree::default_max_depth(size_t prim_count) {
    if (prim_count <= 1) return 8;
    return int(std::lround(8.0 + 1.3 * std::log2(double(prim_count))));
}

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
//
// Where the nlogn build's time goes (session 6, callgrind --branch-sim, x86-64-v3 build,
// the bunny's build: 936M instructions, 6.20M mispredicted branches): split_list 41% of
// the instructions (18 per element, 21.5M elements), this sweep ~19% but 3.4M of the
// mispredictions (1.98M the per-group loop below, which exits after an unpredictable
// number of events; 0.47M the `best` update; 0.86M the prefix / suffix loop exits), the
// classification ~5%. Measured and not adopted: pricing the candidate at every event
// and keeping it by selects only at a group's last event (no per-group loop, no branch
// on `best`): 6.20M -> 4.68M mispredictions but 936M -> 1318M instructions (two prices
// per event instead of per group, ~3 events per group), the same tree, and build /
// Embree (accel_bench, old and new binary back to back twice, load 6-8) bunny 3.37, 3.22
// -> 4.99, 4.59, conference 3.98, 3.80 -> 5.26, 5.13.
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

// The top-down recursion shared by both algorithms. A node's lists live in stacks: its
// primitive list (ascending indices, in both builds) and, for nlogn, its three sorted
// event lists. Splitting a node appends the above child's lists on top of each stack and
// compacts the below child's lists in place over the parent's (a stable filter, so
// order is kept); the below subtree is built, the stacks are cut back, then the above
// subtree is built. Memory is the current path plus the pending above-siblings.
class Builder {
public:
    Builder(const Scene& scene, const KdTree::Config& s, int max_depth, std::vector<KdNode>& nodes,
            std::vector<uint32_t>& prim_indices)
        : bounds_(scene.prim_bounds),
          sah_{s.traversal_cost, s.isect_cost, s.empty_bonus},
          max_prims_(uint32_t(s.max_prims)),
          max_depth_(max_depth),
          presorted_(s.build == KdTree::BuildAlgorithm::NLogN),
          ref_budget_(
              s.max_refs ? *s.max_refs
                         : std::max<uint64_t>(KdTree::kMinRefBudget, KdTree::kMaxRefsPerPrim * scene.triangle_count())),
          nodes_(nodes),
          prim_indices_(prim_indices),
          side_(scene.triangle_count()) {}

    void run(const Bounds3& root) {
        const uint32_t n = uint32_t(bounds_.size());
        Lists lists;
        // The stacks start at the size they reach (the bunny's and the conference's lists
        // peak at 4x the root's): memory not yet used is not touched, so reserving it costs
        // no page faults, and each regrowth it saves copied the stack into fresh pages.
        // Measured (session 5): callgrind, the bunny's build 940M -> 931M instructions (the
        // copies); getrusage over 10 builds: minor faults per build bunny 3089 -> 205,
        // conference 13685 -> 10437, dragon 51124 -> 34263; system time bunny 9.3 -> 0 ms,
        // conference 54 -> 39 ms, dragon 191 -> 130 ms (dragon user + system 1457 -> 1371 ms).
        prims_.reserve(4 * size_t(n));
        for (ListStack<EventKey>& events : events_) events.reserve(8 * size_t(n));
        uint32_t* prims = prims_.grow(n);
        for (uint32_t i = 0; i < n; ++i) prims[i] = i;
        lists.prims = {0, n};
        live_refs_ = n;
        if (presorted_) {
            for (int axis = 0; axis < 3; ++axis) {
                EventKey* ev = events_[axis].grow(2 * size_t(n));
                size_t m = 0;
                for (uint32_t p = 0; p < n; ++p) m = put_events(ev, m, bounds_[p], axis, p);
                events_[axis].truncate(m);
                sort_root_events(ev, m);
                lists.events[axis] = {0, m};
            }
            std::vector<EventKey>().swap(scratch_);  // nlogn needs no scratch below the root
        }
        build_node(root, lists, 0, 0);
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

    static void sort_events(EventKey* ev, size_t m) { std::sort(ev, ev + m); }

    // The root's events on one axis, the largest sort of the nlogn build: a radix sort
    // (base/radix_sort.h) on the position and type bits of the key only. The events were
    // made in ascending primitive order and each pass is stable, so events of equal
    // position and type keep that order, which is the order of the whole key (primitive
    // index included) that sort_events gives: the same list, the same tree. std::sort's
    // comparisons of positions branch as unpredictably as the scene: 2.5M of the bunny
    // build's 8.8M mispredicted branches (callgrind --branch-sim) were this sort.
    void sort_root_events(EventKey* ev, size_t m) {
        scratch_.resize(m);
        radix_sort(std::span<EventKey>(ev, m), std::span<EventKey>(scratch_), int(64 - kPrimBits), kRootSortDigitBits,
                   [](EventKey e) { return e >> kPrimBits; });
    }
    // 34 key bits in 3 passes of 12-bit digits (4096 buckets).
    static constexpr int kRootSortDigitBits = 12;

    // The node's sorted events on `axis`: a slice of the presorted lists (nlogn), or
    // generated from the primitive list and sorted here (pbrt).
    std::span<const EventKey> events_of(const Lists& lists, int axis) {
        if (presorted_) return {events_[axis].data() + lists.events[axis].begin, lists.events[axis].size()};
        scratch_.resize(2 * lists.prims.size());
        EventKey* ev = scratch_.data();
        const uint32_t* prims = prims_.data();
        size_t m = 0;
        for (size_t i = lists.prims.begin; i < lists.prims.end; ++i)
            m = put_events(ev, m, bounds_[prims[i]], axis, prims[i]);
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
            sweep_axis(events_of(lists, axis), axis, node, uint32_t(lists.prims.size()), sah_, best);
            if (best.axis >= 0 && best.cost < leaf_cost) break;
        }
        return best;
    }

    void make_leaf(uint32_t index, Range prims, int depth) {
        const uint32_t count = uint32_t(prims.size());
        const uint32_t* p = prims_.data() + prims.begin;
        if (count == 1) {
            nodes_[index] = KdNode::leaf(1, p[0]);
        } else {
            check_limit(prim_indices_.size() + count, KdNode::kMaxIndex, "primitive references");
            nodes_[index] = KdNode::leaf(count, uint32_t(prim_indices_.size()));
            prim_indices_.insert(prim_indices_.end(), p, p + count);
        }
        live_refs_ -= count;
        leaf_refs_ += count;
        deepest_leaf_ = std::max(deepest_leaf_, depth);
    }

    void check_limit(uint64_t value, uint64_t limit, const char* what) const {
        if (value > limit)
            throw std::runtime_error("kdtree: build exceeds its limit of " + std::to_string(limit) + " " + what +
                                     " (references: " + std::to_string(KdTree::kMaxRefsPerPrim) +
                                     " per triangle, at least " + std::to_string(KdTree::kMinRefBudget) +
                                     "; nodes and references: 2^30 - 1); lower max_depth or raise "
                                     "max_prims or traversal_cost");
    }

    // Splits one list (a range of `stack`) by side_: the above part is appended at the
    // top, the below part compacted in place. Returns {below, above}. One pass, written
    // without branches on the side, which is as unpredictable as the scene: every element
    // is stored to both outputs and each output's end advances only when the element
    // belongs there (below is compacted in place: its write index never passes the read
    // index). `keep` masks the sides wanted (kBelow, kAbove or kBoth): a child that will
    // be a leaf needs no event lists, so its part is not kept (a side not kept comes back
    // empty). (Two passes, one per side, read each element and its side twice: 464M
    // instructions of the bunny's 1.12G build against 380M for this one.)
    // Measured in session 10 and not adopted: keeping no event lists for children below 16
    // (64) primitives, which then make and sort their own events per axis as the pbrt build
    // does (the same tree): build / Embree bunny 3.25, 3.29 -> 4.20, 4.29 (4.95, 4.86),
    // conference 3.61, 3.53 -> 5.25, 5.24 (7.46, 7.29). Splitting the sorted lists costs less
    // than sorting even a small node's events; likely std::sort's mispredicted comparisons, as
    // in the root sort's profile (sort_root_events), not profiled here.
    template <class T, class PrimOf>
    std::pair<Range, Range> split_list(ListStack<T>& stack, Range r, PrimOf prim, uint8_t keep = kBoth) {
        const size_t above_begin = stack.size();
        T* above = stack.grow(r.size());
        T* list = stack.data() + r.begin;  // after grow(): it may move the stack
        const uint8_t* side = side_.data();
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
    bool leaf_by_limits(size_t n, int depth) const { return n <= max_prims_ || depth >= max_depth_; }

    void build_node(const Bounds3& node, const Lists& lists, int depth, int bad_refines) {
        check_limit(nodes_.size() + 1, KdNode::kMaxIndex, "nodes");
        const uint32_t index = uint32_t(nodes_.size());
        nodes_.emplace_back();
        const uint32_t n = uint32_t(lists.prims.size());
        if (leaf_by_limits(n, depth)) return make_leaf(index, lists.prims, depth);

        const float leaf_cost = sah_.isect * float(n);
        const Split split = choose_split(node, lists, leaf_cost);
        // pbrt's termination: a split dearer than the leaf is tolerated three times on a
        // path (it may enable cheap splits below), one much dearer only for big nodes.
        const bool bad = split.axis >= 0 && split.cost > leaf_cost;
        if (bad) ++bad_refines;
        if (split.axis < 0 || (split.cost > 4.0f * leaf_cost && n < 16) || bad_refines == 3)
            return make_leaf(index, lists.prims, depth);
        counters_.bad_refines += bad;

        const uint32_t* prims = prims_.data();
        for (size_t i = lists.prims.begin; i < lists.prims.end; ++i)
            side_[prims[i]] = classify(bounds_[prims[i]], split.axis, split.position, split.planar_below);
        Lists below, above;
        std::tie(below.prims, above.prims) = split_list(prims_, lists.prims, [](uint32_t p) { return p; });
        if (presorted_) {
            // Only a child that will be split needs its sorted events (a leaf reads its
            // primitive list alone); at the last level neither does.
            const auto splits = [&](Range r) { return !leaf_by_limits(r.size(), depth + 1); };
            const uint8_t keep = uint8_t((splits(below.prims) ? kBelow : 0) | (splits(above.prims) ? kAbove : 0));
            if (keep)
                for (int axis = 0; axis < 3; ++axis)
                    std::tie(below.events[axis], above.events[axis]) = split_list(
                        events_[axis], lists.events[axis], [](EventKey e) { return prim_of(e); }, keep);
        }
        live_refs_ += below.prims.size() + above.prims.size() - n;
        check_limit(leaf_refs_ + live_refs_, ref_budget_, "primitive references");

        Bounds3 below_bounds = node, above_bounds = node;
        below_bounds.upper[split.axis] = above_bounds.lower[split.axis] = split.position;
        const size_t saved_prims = prims_.size();
        size_t saved_events[3];
        for (int axis = 0; axis < 3; ++axis) saved_events[axis] = events_[axis].size();

        build_node(below_bounds, below, depth + 1, bad_refines);
        prims_.truncate(saved_prims);
        for (int axis = 0; axis < 3; ++axis) events_[axis].truncate(saved_events[axis]);
        nodes_[index] = KdNode::interior(split.axis, split.position, uint32_t(nodes_.size()));
        build_node(above_bounds, above, depth + 1, bad_refines);
    }

    const std::vector<Bounds3>& bounds_;
    SahConstants sah_;
    uint32_t max_prims_;
    int max_depth_;
    bool presorted_;
    uint64_t ref_budget_;
    std::vector<KdNode>& nodes_;
    std::vector<uint32_t>& prim_indices_;
    std::vector<uint8_t> side_;      // per primitive, set for the node being split
    ListStack<uint32_t> prims_;      // primitive lists
    ListStack<EventKey> events_[3];  // nlogn: sorted event lists per axis
    std::vector<EventKey> scratch_;  // one node's events on one axis, sorted on the spot
    BuildCounters counters_;
    uint64_t leaf_refs_ = 0;  // references held by the leaves made so far
    uint64_t live_refs_ = 0;  // references in the lists still to be split
    int deepest_leaf_ = 0;
};

}  // namespace

void KdTree::build(const Scene& scene) {
    const size_t n = scene.triangle_count();
    if (n > kPrimMask)
        throw std::runtime_error("kdtree: scene '" + scene.name + "' has " + std::to_string(n) +
                                 " triangles; at most 2^30 - 1 are supported");
    if (scene.prim_bounds.size() != n) throw std::runtime_error("kdtree: scene '" + scene.name + "' is not finalized");
    corners_.resize(n);
    for (uint32_t i = 0; i < n; ++i) corners_[i] = {scene.vertex(i, 0), scene.vertex(i, 1), scene.vertex(i, 2)};
    bounds_ = scene.bounds;
    nodes_.clear();
    prim_indices_.clear();
    max_depth_used_ = config_.max_depth ? *config_.max_depth : default_max_depth(n);
    // Only a scene of more than 2^92 triangles would get a default above the limit.
    max_depth_used_ = std::min(max_depth_used_, kMaxDepthLimit);

    BuildCounters counters;
    int deepest = 0;
    if (n > 0) {
        Builder builder(scene, config_, max_depth_used_, nodes_, prim_indices_);
        try {
            builder.run(bounds_);
        } catch (...) {
            // A build that stopped at a limit leaves no half tree behind: an empty tree
            // answers every ray with a miss, never with a wrong hit.
            nodes_ = {};
            prim_indices_ = {};
            throw;
        }
        counters = builder.counters();
        deepest = builder.deepest_leaf();
    }
    nodes_.shrink_to_fit();
    prim_indices_.shrink_to_fit();
    bad_refines_ = counters.bad_refines;
    deepest_leaf_ = deepest;
}

uint64_t KdTree::memory_bytes() const {
    return nodes_.size() * sizeof(KdNode) + prim_indices_.size() * sizeof(uint32_t) +
        corners_.size() * sizeof(corners_[0]);
}

// Walks the tree with each node's box (tree_tally.h). sah_cost_build is the same sum with
// this build's C_T and C_I (pbrt's model without the empty bonus), what its SAH minimised.
BuildStats measure_kdtree(const KdTree& tree) {
    const std::span<const KdNode> nodes = tree.nodes();
    TreeTally t;
    t.nodes = nodes.size();
    t.max_depth = uint64_t(tree.deepest_leaf());
    t.memory_bytes = tree.memory_bytes();
    t.root_area = nodes.empty() ? 0.0 : double(tree.bounds().area());
    uint64_t empty_leaves = 0;
    struct Item {
        uint32_t node;
        Bounds3 box;
    };
    std::vector<Item> todo;
    if (!nodes.empty()) todo.push_back({0, tree.bounds()});
    while (!todo.empty()) {
        const Item it = todo.back();
        todo.pop_back();
        const KdNode& node = nodes[it.node];
        if (node.is_leaf()) {
            t.leaf(it.box.area(), node.prim_count());
            empty_leaves += node.prim_count() == 0;
        } else {
            t.inner(it.box.area());
            Bounds3 below = it.box, above = it.box;
            below.upper[node.axis()] = above.lower[node.axis()] = node.split();
            todo.push_back({node.above_child(), above});
            todo.push_back({it.node + 1, below});
        }
    }
    BuildStats s = t.stats();
    const KdTree::Config& config = tree.config();
    if (const auto build_cost = t.sah_cost(config.traversal_cost, config.isect_cost))
        s.extra["sah_cost_build"] = *build_cost;
    s.extra["prim_refs"] = double(t.prim_refs);
    s.extra["empty_leaves"] = double(empty_leaves);
    s.extra["bad_refines"] = double(tree.bad_refines());
    s.extra["max_depth_limit"] = double(tree.max_depth_used());
    return s;
}

BuildStats KdTree::build_stats() const { return measure_kdtree(*this); }

// ---- traversal (report 4.2.2, Figures 15-16; pbrt's KdTreeAccel::Intersect) ------------
//
// The ray is clipped to the root box, giving [t_min, t_max]. At an interior node the
// plane is crossed at t_split; the child on the side the ray comes from ("first": below
// when the direction component is positive, by its sign bit so -0.0 counts as negative)
// covers [t_min, t_split], the other [t_split, t_max]. If t_split > t_max the ray leaves
// the node before the plane (first child only); if t_split < t_min it crossed before
// entering (second only); otherwise both, first now, second pushed. A ray with a zero
// direction component gets t_split = +-inf and one child; one lying IN the plane gets
// NaN, fails both tests and visits both children over the whole range (the min/max below
// are written so that NaN yields the other argument). Choosing "first" by direction, not
// by which side the origin lies on, keeps this right for any ray.tmin.
//
// Leaves test their triangles over the whole remaining ray interval [ray.tmin, best), not
// just the leaf's [t_min, t_max]: a primitive can stick out of the leaf and be hit
// beyond it. Such a hit is kept but does not end the traversal; only a hit closer than
// the next node's t_min does (nodes leave the stack in front-to-back order).
//
// Conservative in float (Ize 2013, as intersect_box): t_split is rounded up to three
// times, so each comparison uses the interval [slack_below, slack_above](t_split) that
// holds its true value, and the ranges handed to the children are widened the same way
// (they overlap by the slack), so a node's [t_min, t_max] always contains its true range
// and a child is culled only when the ray certainly misses it. Without this the tree
// leaked rays aimed exactly at a vertex lying on two split planes (robustness case 1:
// origin (-0.5, 0.25, 0.125), direction (0.33937797, 0.443780482, 0.577046454), vertex
// at t = 1): the x-plane through the vertex gave t = 1 exactly and the y-plane through
// it t_split = 0.99999994, so the node entered at t_min = 1 beyond the x-plane dropped
// its below-y child as "crossed before entering" — the only child holding a triangle
// that contains the vertex (its y range ends on the plane, so it is classified below).

namespace {

struct StackEntry {
    uint32_t node;
    float t_min, t_max;
};

// Visits the leaves a ray passes, front to back, over [t_min, t_max] clipped to the root
// box. visit_leaf(leaf) (a reference into `nodes`) returns false to stop. keep_going(t_min)
// is asked before each popped node: closest-hit stops once its best hit lies before that
// node.
//
// Where the time goes (session 6, callgrind with --branch-sim and --cache-sim, LL 512 KB;
// the 640x480 primary + shadow rays, instructions per ray, before this session's changes):
// bunny closest hit 870 (interior steps 46%, setup — RayPrecomp, root clip, WatertightRay,
// is_valid_ray — 27%, triangle tests 15%, leaf loop 11%), 12.8 node visits and 1.65 tests
// a ray; any hit 3980 (interior 53%, triangles 24%, leaf 13%), 69 visits and 12.3 tests.
// Conference closest hit 4212 (interior 40%, triangles 37%, leaf 15%), 55 visits and 19
// tests. Data misses are not the cost: 0.13 LL misses a ray in the interior steps and
// ~0.1 in the leaves (the rest is reading the rays). Branch mispredictions are: callgrind
// counts 11 a ray (bunny closest), 61 (bunny any), 53 (conference closest), three quarters
// of them in the interior steps (the leaf test and the near / far choice).
//
// The step below is branchy on purpose. Measured (conference, closest / any seconds,
// interleaved, load 10-14): these branches 1.38 / 0.97; the single-child case by a
// conditional move (one branch left, for "both") 1.76-2.02 / 1.29-1.38; fully branch-free
// (the entry always written, the stack pointer advanced by the "both" flag, the next
// index by conditional moves) 2.13 / 1.50-1.60. The predicted branch lets the next node's
// load start before t_split is known; a conditional move puts the whole step (load, t_split,
// slack, compare) on the critical path of every node, and that costs more than the
// mispredictions it saves.
//
// Changes of session 6 (answers and counters identical on every ray of the bunny and the
// conference; callgrind instructions closest / any): bunny 267.2M / 210.9M -> 250.2M /
// 185.2M for this file's changes (one inlined leaf loop for one and several references:
// the one-reference leaf called hit_triangle out of line; the stack addressed by pointer;
// the above-first mask per axis loaded instead of shifted out of a bit set; the closest-hit
// stop test computing slack_below only when a hit lies before the node), then 240.7M /
// 181.1M with the triangle's corners by reference (triangle.h) and the one-instruction
// slack cap (geometry.h), then 231.3M / 166.7M with the triangle test's outside check
// before its zero check (triangle.h; 65 instead of 81 instructions a test on the
// conference); conference 1293.8M / 828.1M -> 1152.4M / 729.6M -> 1045.3M / 664.8M. In all
// -13% / -21% (bunny), -19% / -20% (conference). Per ray after them: bunny closest hit 753
// (interior 46%, setup 28%, triangles 15%, leaf 10%), any hit 3147; conference closest hit
// 3403 (interior 43%, triangles 36%, leaf 13%), any hit 2164.
// Measured and not adopted: WatertightRay holding org[kx], org[ky], org[kz] so that the
// test need not load them by index: +2.5% / +1.0% instructions (bunny), +1.6% / +1.8%
// (conference) — one more live value in a loop already short of registers.
// Not tried, for what the profile says: a per-leaf copy of the triangles in leaf order (as
// FlatBvh keeps for the BVH) would save the index load of a test, but the leaves' data
// misses are already ~0.1 a ray, and it would cost 36 bytes a reference: +17 MB on the
// bunny (9.05 MB today, 6.8 references a triangle), +172 MB on the conference (44.3 MB,
// 14.4 a triangle). Prefetching the pushed child, for the same reason (0.13 misses a ray).
template <class C, class VisitLeaf, class KeepGoing>
void traverse(std::span<const KdNode> nodes, const Bounds3& bounds, const Ray& ray, C& counters, VisitLeaf&& visit_leaf,
              KeepGoing&& keep_going) {
    if (nodes.empty()) return;
    const RayPrecomp rp(ray);
    counters.box();
    const BoxHit clip = intersect_box(bounds, rp, ray.tmin, ray.tmax);
    if (!clip.hit()) return;
    // tfar is already widened by intersect_box; tnear is widened here the same way.
    float t_min = slack_below(clip.tnear), t_max = clip.tfar;
    // Per-axis ray data as plain arrays: indexing a Vec3 by a run-time axis is a chain
    // of selects, and this loop indexes by the node's axis at every step.
    const float org[3] = {rp.org.x, rp.org.y, rp.org.z};
    const float inv_dir[3] = {rp.inv_dir.x, rp.inv_dir.y, rp.inv_dir.z};
    // All ones on the axes where the ray meets the above child first: first = below ^
    // ((below ^ above) & mask), one load where shifting a per-ray bit set out took three.
    const uint32_t above_first[3] = {0u - uint32_t(rp.near_is_upper[0]), 0u - uint32_t(rp.near_is_upper[1]),
                                     0u - uint32_t(rp.near_is_upper[2])};
    StackEntry stack[KdTree::kMaxDepthLimit];
    StackEntry* top = stack;
    uint32_t index = 0;
    for (;;) {
        counters.node();
        const KdNode& node = nodes[index];
        if (!node.is_leaf()) {
            const int axis = node.axis();
            const float t_split = (node.split() - org[axis]) * inv_dir[axis];
            const uint32_t below = index + 1, above = node.above_child();
            const uint32_t swap = (below ^ above) & above_first[axis];
            const uint32_t first = below ^ swap, second = above ^ swap;
            // "first only" is split_lo > t_max and "second only" split_hi < t_min. As
            // split_lo <= t_split <= split_hi (NaN compares false either way), each is the
            // plain comparison of t_split AND the one with the slack: the same decisions, but
            // the branch that chooses the child waits for t_split only, and the slack's
            // comparison is a second branch, nearly always taken with the first (as the wide
            // BVH's widened_mask, wbvh_simd.h). A mispredicted choice is found out the slack's
            // latency (abs, multiply, min, subtract) sooner. Measured (session 8, trace / Embree,
            // four interleaved A/B rounds on two models, two on the others, load ~1): bunny
            // 3.54 3.46 3.46 3.48 -> 3.27 3.35 3.28 3.21, igea 3.74 3.78 3.79 3.79 -> 3.67 3.58
            // 3.63 3.63, dragon 3.34 3.39 3.36 3.38 3.35 3.32 -> 3.33 3.22 3.17 3.43 3.20 3.19,
            // conference 2.86 2.83 2.87 2.92 2.93 2.85 -> 2.90 3.11 2.86 2.87 2.87 2.87 (no change);
            // mailbox=true within the noise. Answers and counters identical (every ray's
            // totals on the bunny and the conference, both mailbox settings; ctest).
            if (t_split > t_max) {
                if (slack_below(t_split) > t_max) [[likely]] {
                    index = first;
                    continue;
                }
            } else if (t_split < t_min) {
                if (slack_above(t_split) < t_min) [[likely]] {
                    index = second;
                    continue;
                }
            }
            const float split_lo = slack_below(t_split), split_hi = slack_above(t_split);
            *top++ = {second, split_lo > t_min ? split_lo : t_min, t_max};
            t_max = split_hi < t_max ? split_hi : t_max;
            index = first;
            continue;
        }
        if (!visit_leaf(node) || top == stack) return;
        --top;
        index = top->node;
        t_min = top->t_min;
        t_max = top->t_max;
        if (!keep_going(t_min)) return;
    }
}

}  // namespace

const uint32_t* KdTree::leaf_prims(const KdNode& leaf, uint32_t& count) const {
    count = leaf.prim_count();
    return count == 1 ? leaf.single_prim_run() : prim_indices_.data() + leaf.prim_offset();
}

// Inlined into each leaf loop (GCC otherwise calls it: the call and its argument set-up cost
// ~10 instructions per test).
[[gnu::always_inline]] inline bool KdTree::hit_triangle(const WatertightRay& wr, uint32_t prim, float tmin, float tmax,
                                                        Hit& hit) const {
    const std::array<Vec3, 3>& tri = corners_[prim];
    if (!intersect_triangle(wr, tri[0], tri[1], tri[2], tmin, tmax, hit.t, hit.u, hit.v)) return false;
    hit.prim = prim;
    return true;
}

// The triangles a ray tested, in a direct-mapped table indexed by the low bits of the
// triangle's index: a triangle evicts only one whose index shares them, and leaves along
// a ray share triangles mostly with the leaves just before them (the triangle straddles
// their common plane), so the few tests a ray makes rarely collide (an eviction only
// costs a repeated test, never an answer). One scalar load, compare and store per test.
// The 8-entry ring searched with one vector compare it replaces reloaded as a vector the
// entry it had just stored (a failed store-to-load forward) on most tests: trace /
// Embree without mailbox, ring, this table (accel_bench, interleaved, load 7): bunny
// 3.79, 4.01, 3.69; conference 3.63, 3.40, 2.99 (the conference's primary + shadow rays
// test 9.37M triangles without a mailbox, 5.21M with the ring, 4.89M with this table).
class Mailbox {
public:
    Mailbox() { std::fill(std::begin(ids_), std::end(ids_), kInvalidId); }
    // Whether `prim` was tested already; if not, remembers it.
    bool seen(uint32_t prim) {
        uint32_t& slot = ids_[prim & (kSize - 1)];
        const bool found = slot == prim;
        slot = prim;
        return found;
    }

private:
    static constexpr uint32_t kSize = 64;
    uint32_t ids_[kSize];
};

// No mailbox: never seen.
struct NoMailbox {
    static constexpr bool seen(uint32_t) { return false; }
};

// The leaf loop both queries share: each of a leaf's triangles the mailbox has not seen is
// counted and handed to test(prim), the shear constants made first if this is the ray's
// first leaf with a triangle; stops (returns false) when test returns false.
template <class Mailbox, class C, class Test>
inline bool for_untested_triangles(const uint32_t* prims, uint32_t count, const Ray& ray,
                                   std::optional<WatertightRay>& wr, Mailbox& mailbox, C& counters, Test&& test) {
    if (count != 0 && !wr) wr.emplace(ray);
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t prim = prims[i];
        if (mailbox.seen(prim)) continue;
        counters.prim();
        if (!test(prim)) return false;
    }
    return true;
}

// Measured and not adopted (session 5): leaves of 2+ references testing their triangles 4
// at a time in one SSE watertight test (the wide BVH's packet test moved to a shared
// header; packets at half the leaf's prim_indices_ offset, answers and prim_tests
// identical to this loop; branch s5-raysets, 2c6016a). Callgrind, 640x480 primary + shadow rays, closest_hits /
// any_hits instructions: bunny 263.8M / 210.4M -> 244.5M / 175.8M, conference 1290.6M /
// 825.6M -> 1044.0M / 688.1M. But the packets copy a triangle per reference (up to 80 bytes
// against the 4-byte index; the bunny's tree holds 6.8 references per triangle, the
// conference's 14.4): bunny memory_bytes 9.05 -> 42.4 MB, build +6% instructions (60M of
// packing), and the extreme-case catalogue's memory bound (4096 bytes per triangle) failed
// on overlapping soups. Trace / Embree, interleaved, load 6-9: bunny 3.81, 3.71 -> 3.46,
// 3.48; conference 3.17 -> 3.26 (all references packed) and 3.44, 3.35 -> 4.06, 4.01 with
// packets only within 1024 bytes per triangle (the conference then falls back to this loop,
// which as a second template variant cost +5% instructions: 1357M / 857M).
template <bool kMailbox, class C>
void KdTree::intersect_with(const Ray& ray, Hit& hit, C& counters) const {
    // The shear constants are made at the first leaf with a triangle, not before the
    // traversal: many rays (the bunny's primary rays that pass beside it) never get there.
    // Callgrind, bunny closest / any: 231.3M / 166.7M -> 209.5M / 163.6M instructions; trace
    // / Embree within the noise (bunny 3.62 3.57 3.52 -> 3.79 3.57 3.49, conference 3.21 3.17
    // 3.10 -> 3.23 3.09 2.99, back to back, load 6).
    std::optional<WatertightRay> wr;
    float best = ray.tmax;
    std::conditional_t<kMailbox, Mailbox, NoMailbox> mailbox;
    traverse(
        nodes_, bounds_, ray, counters,
        [&](const KdNode& leaf) {
            uint32_t count;
            const uint32_t* prims = leaf_prims(leaf, count);
            return for_untested_triangles(prims, count, ray, wr, mailbox, counters, [&](uint32_t prim) {
                if (hit_triangle(*wr, prim, ray.tmin, best, hit)) best = hit.t;
                return true;
            });
        },
        // next_t_min is a lower bound of the node's true entry distance, but a hit in it
        // is a computed t that may round below its true value: stop only when the best
        // hit lies before that node by more than the slack, so a hit at the node's
        // boundary (a vertex on its plane) is never skipped for a farther one.
        [&](float next_t_min) { return !(best < next_t_min && best < slack_below(next_t_min)); });
}

template <bool kMailbox, class C>
bool KdTree::occluded_with(const Ray& ray, C& counters) const {
    std::optional<WatertightRay> wr;  // made at the first leaf with a triangle, as above
    bool found = false;
    std::conditional_t<kMailbox, Mailbox, NoMailbox> mailbox;
    traverse(
        nodes_, bounds_, ray, counters,
        [&](const KdNode& leaf) {
            Hit scratch;
            uint32_t count;
            const uint32_t* prims = leaf_prims(leaf, count);
            return for_untested_triangles(prims, count, ray, wr, mailbox, counters, [&](uint32_t prim) {
                if (!hit_triangle(*wr, prim, ray.tmin, ray.tmax, scratch)) return true;
                found = true;
                return false;  // stop at the first hit
            });
        },
        [](float) { return true; });
    return found;
}

template <class C>
void KdTree::intersect(const Ray& ray, Hit& hit, C& counters) const {
    if (config_.mailbox) intersect_with<true>(ray, hit, counters);
    else intersect_with<false>(ray, hit, counters);
}

template <class C>
bool KdTree::occluded(const Ray& ray, C& counters) const {
    return config_.mailbox ? occluded_with<true>(ray, counters) : occluded_with<false>(ray, counters);
}

ACCELBENCH_INSTANTIATE_RAY_QUERIES(KdTree);

}  // namespace accelbench
