#include "accelbench/accel/bvh/lbvh.h"

#include <algorithm>
#include <bit>
#include <future>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "accelbench/accel/bvh/bvh_metrics.h"
#include "accelbench/accel/bvh/bvh_top_down.h"
#include "accelbench/accel/bvh/morton_code.h"
#include "accelbench/base/param_table.h"
#include "accelbench/base/radix_sort.h"

namespace accelbench {

namespace {

// The parameters, each once: its row and its Config member, whose initializer is the default.
const ParamTable<Lbvh::Config>& lbvh_params() {
    using C = Lbvh::Config;
    static const ParamTable<C> rows = {
        enum_param("build", &C::build, Lbvh::kBuildNames,
                   "karras: split by binary search, boxes bottom-up, O(N) after the sort (Karras 2012); report: the "
                   "report's Algorithm 2, each node's box fitted from its primitives and the split by a linear scan "
                   "(both give the same tree); median: the codes and the sort, then the median BVH's build and tree, "
                   "the LBVH the report's section 5.2 measured (one thread)"),
        int_param("bits", &C::bits, kMortonMinBits, kMortonMaxBits<uint64_t>,
                  "Morton grid bits per axis (2^bits cells); up to 10 sorts 32-bit codes, 11..21 64-bit codes"),
        int_param("max_prims", &C::max_prims, 1, BvhNode::kMaxLeafPrims,
                  "a range of at most this many primitives becomes a leaf (the report: 1)"),
        int_param("max_depth", &C::max_depth, 0, 1000,
                  "a node at this depth becomes a leaf whatever its size (root: depth 0; the report: 50)"),
        threads_param("threads", &C::threads, "build threads (0 = all cores); the tree is the same for every value"),
        int_param("task_threshold", &C::task_threshold, 1, 1e9,
                  "a subtree goes to another thread only above this many primitives (the report: 100)"),
        int_param("sort_digit_bits", &C::sort_digit_bits, kRadixMinDigitBits, kRadixMaxDigitBits,
                  "radix sort digit width: bits per counting pass"),
        bvh_traversal_param(&C::traversal),
    };
    return rows;
}

}  // namespace

AcceleratorInfo Lbvh::info() {
    return {.name = "lbvh",
            .description =
                "linear BVH (report section 3): Morton codes of the centroids, one radix sort, split at the "
                "highest differing code bit (Karras 2012 or the report's Algorithm 2, the same tree); "
                "optional subtree threads",
            .params = lbvh_params().specs(),
            .create = [](const ParamSet& p) { return std::make_unique<Lbvh>(p); },
            .label = fixed_label("LBVH"),
            .depth_limit = [](const ParamSet& p) -> std::optional<uint64_t> { return Config::from(p).max_depth; }};
}

Lbvh::Config Lbvh::Config::from(const ParamSet& p) { return lbvh_params().from(p); }

Lbvh::Lbvh(const ParamSet& params) : Lbvh(Config::from(params)) {}

Lbvh::Lbvh(const Config& config) : config_(config) {}

Lbvh::Counts& Lbvh::Counts::operator+=(const Counts& o) {
    equal_code_splits += o.equal_code_splits;
    forced_leaves += o.forced_leaves;
    degenerate_splits += o.degenerate_splits;
    tasks += o.tasks;
    sort_passes += o.sort_passes;
    sort_skipped_passes += o.sort_skipped_passes;
    return *this;
}

namespace {

// Builds the tree over primitives sorted by Morton code. One builder serves all threads;
// what a thread writes (its node buffer, its counts) is passed down the recursion.
//
// Which subtrees go to other threads is decided by a thread budget passed down the
// recursion (the root has `threads`; a hand-off splits a node's budget between its
// children by their primitive counts), not by which threads happen to be free: so the
// hand-offs, and the build_tasks count reported, are a property of the tree and the
// parameters, the same in every build (the harness checks that builds are reproducible).
// At most `threads` threads are live, as the budgets of live subtrees sum to it.
template <class Code>
class LbvhBuilder {
public:
    // `sorted_bounds[i]` is the box of the primitive sorted_[i] refers to.
    LbvhBuilder(const std::vector<KeyValue<Code>>& sorted, const std::vector<Bounds3>& sorted_bounds,
                const Lbvh::Config& config)
        : sorted_(sorted), sorted_bounds_(sorted_bounds), config_(config) {}

    // Builds the subtree over sorted_[begin, end) at `depth`, appending its nodes to `out`
    // in depth-first order (its root first). Node indices are relative to out's start.
    // Returns the subtree's bounds. `threads`: the subtree's thread budget, its own thread
    // included. Small enough to be inlined into build_inner, so that the leaves — half of
    // all nodes — cost no call of their own.
    Bounds3 build(uint32_t begin, uint32_t end, uint32_t depth, std::vector<BvhNode>& out, Lbvh::Counts& counts,
                  int threads) {
        const uint32_t count = end - begin;
        if (count <= config_.max_prims || depth >= config_.max_depth) return build_leaf(begin, end, out, counts);
        return build_inner(begin, end, depth, out, counts, threads);
    }

private:
    Bounds3 build_leaf(uint32_t begin, uint32_t end, std::vector<BvhNode>& out, Lbvh::Counts& counts) const {
        const uint32_t count = end - begin;
        if (count > config_.max_prims) {
            if (count > BvhNode::kMaxLeafPrims)
                throw std::runtime_error("lbvh: a leaf of " + std::to_string(count) + " primitives at max_depth " +
                                         std::to_string(config_.max_depth) + " exceeds the node format's " +
                                         std::to_string(BvhNode::kMaxLeafPrims));
            ++counts.forced_leaves;
        }
        const Bounds3 b = global_aabb(begin, end);
        out.push_back(BvhNode::leaf(b, begin, count));
        return b;
    }

    // The box of the primitives sorted_[begin, end): the report's getGlobalAABB.
    Bounds3 global_aabb(uint32_t begin, uint32_t end) const {
        Bounds3 b = sorted_bounds_[begin];
        for (uint32_t i = begin + 1; i < end; ++i) b.extend(sorted_bounds_[i]);
        return b;
    }

    Bounds3 build_inner(uint32_t begin, uint32_t end, uint32_t depth, std::vector<BvhNode>& out, Lbvh::Counts& counts,
                        int threads) {
        const uint32_t self = uint32_t(out.size());
        out.emplace_back();  // written once the node's box is known
        // Algorithm 2 fits the node's box from its primitives before it splits; Karras's
        // build leaves it to the children's boxes below.
        const bool report = config_.build == Lbvh::Build::report;
        const Bounds3 fitted = report ? global_aabb(begin, end) : Bounds3{};
        const Split split = report ? scan_split(begin, end) : find_split(begin, end);
        if (split.axis < 0) ++counts.equal_code_splits;

        Bounds3 left, right;
        uint32_t second;
        if (threads > 1 && end - split.index > config_.task_threshold) {
            // The second child's subtree goes to another thread, into its own buffer; this
            // thread builds the first child meanwhile, then appends the second's nodes
            // right after the first's: the order a one-thread build produces. Each side
            // keeps at least one thread of the budget, the rest by primitive count.
            const int task_threads =
                std::clamp(int(int64_t(threads) * (end - split.index) / (end - begin)), 1, threads - 1);
            ++counts.tasks;
            std::vector<BvhNode> task_nodes;
            Lbvh::Counts task_counts;
            auto task = std::async(std::launch::async, [&] {
                task_nodes.reserve(2 * size_t(end - split.index) - 1);
                return build(split.index, end, depth + 1, task_nodes, task_counts, task_threads);
            });
            left = build(begin, split.index, depth + 1, out, counts, threads - task_threads);
            right = task.get();
            second = uint32_t(out.size());
            append_relocated(out, task_nodes);
            counts += task_counts;
        } else {
            left = build(begin, split.index, depth + 1, out, counts, threads);
            second = uint32_t(out.size());
            right = build(split.index, end, depth + 1, out, counts, threads);
        }
        const Bounds3 b = report ? fitted : merge(left, right);
        out[self] = BvhNode::inner(b, second, split.axis >= 0 ? split.axis : b.largest_axis());
        return b;
    }

    struct Split {
        uint32_t index;  // first primitive of the second child
        int axis;        // the axis of the code bit split at; -1: all codes equal
    };

    // Karras 2012, section 4 (findSplit), the report's "search for the first leading bit
    // change": the range's codes are sorted, so they share all bits above the highest bit
    // in which its first and last codes differ, and that bit is 0 for a prefix of the
    // range and 1 for the rest; binary search for the first 1. When the first and last
    // codes are equal, so are all between (several centroids in one grid cell): no bit
    // can split them, and the middle of the range keeps the tree balanced.
    Split find_split(uint32_t begin, uint32_t end) const {
        const Code first = sorted_[begin].key, last = sorted_[end - 1].key;
        if (first == last) return {begin + (end - begin) / 2, -1};
        const int bit = std::bit_width(Code(first ^ last)) - 1;
        const Code mask = Code(1) << bit;
        // Branch-free lower bound: `base` only ever moves onto codes with the bit clear
        // (it starts on the first code, which has it clear as first < last), and the first
        // code with the bit set stays within (base, base + size]. A conditional move picks
        // the half, not a branch: which half wins is a coin toss a predictor would lose
        // half the time.
        uint32_t base = begin, size = end - begin;
        while (size > 1) {
            const uint32_t half = size / 2;
            base = (sorted_[base + half].key & mask) == 0 ? base + half : base;
            size -= half;
        }
        return {base + 1, morton_bit_axis(bit)};
    }

    // The report's findSplitPoint (section 3.1, "we start with the sorted Morton code and
    // search for the first leading bit change"): a linear scan from the range's start for
    // the first code whose highest bit differing between the first and last codes is set.
    // The boundary is the one find_split's binary search finds, at O(n) instead of
    // O(log n); equal codes split in the middle as there.
    Split scan_split(uint32_t begin, uint32_t end) const {
        const Code first = sorted_[begin].key, last = sorted_[end - 1].key;
        if (first == last) return {begin + (end - begin) / 2, -1};
        const int bit = std::bit_width(Code(first ^ last)) - 1;
        const Code mask = Code(1) << bit;
        uint32_t i = begin + 1;
        while ((sorted_[i].key & mask) == 0) ++i;  // stops at the latest at end - 1
        return {i, morton_bit_axis(bit)};
    }

    // Appends a subtree built in its own buffer: its inner nodes' second-child indices
    // were relative to that buffer and move by where it lands. Leaves index the sorted
    // primitive array, which is shared, and need no change.
    static void append_relocated(std::vector<BvhNode>& out, const std::vector<BvhNode>& subtree) {
        const uint32_t base = uint32_t(out.size());
        out.insert(out.end(), subtree.begin(), subtree.end());
        for (size_t i = base; i < out.size(); ++i)
            if (!out[i].is_leaf()) out[i].index += base;
    }

    const std::vector<KeyValue<Code>>& sorted_;
    const std::vector<Bounds3>& sorted_bounds_;
    const Lbvh::Config& config_;
};

}  // namespace

void Lbvh::build(const Scene& scene) {
    if (config_.bits <= kMortonMaxBits<uint32_t>) build_with<uint32_t>(scene);
    else build_with<uint64_t>(scene);
}

template <class Code>
void Lbvh::build_with(const Scene& scene) {
    SortBuffers<Code>& buffers = [this]() -> SortBuffers<Code>& {
        if constexpr (sizeof(Code) == 4) return sort32_;
        else return sort64_;
    }();
    std::vector<KeyValue<Code>>& sorted = buffers.sorted;
    // The tree is rebuilt in place, reusing its arrays' capacity; a build that throws
    // leaves an empty tree behind, not half of one.
    bvh_.nodes.clear();
    bvh_.prim_ids.clear();
    counts_ = {};
    const size_t n = scene.triangle_count();
    try {
        if (n > 0) {
            if (n > UINT32_MAX / 2) throw std::runtime_error("lbvh: scene '" + scene.name + "' has too many triangles");
            // Codes over the centroid bounds, then one sort.
            const MortonQuantizer quantizer(point_bounds(scene.centroids), config_.bits);
            sorted.resize(n);
            for (size_t i = 0; i < n; ++i) sorted[i] = {quantizer.code<Code>(scene.centroids[i]), uint32_t(i)};
            const RadixSortStats sort = radix_sort(sorted, buffers.scratch, 3 * config_.bits, config_.sort_digit_bits);
            counts_.sort_passes = uint64_t(sort.passes);
            counts_.sort_skipped_passes = uint64_t(sort.skipped_passes);
            if (config_.build == Build::median) {
                // The report's LBVH: after the codes and the sort, the median BVH's build
                // over the scene, so the tree is the median BVH's bit for bit.
                BvhMedianSplit median;
                BvhTopDownCounts top_down;
                bvh_ = build_bvh_top_down(scene, {config_.max_prims, config_.max_depth, BvhAxisRule::longest}, median,
                                          top_down);
                counts_.forced_leaves = top_down.forced_leaves;
                counts_.degenerate_splits = top_down.degenerate_splits;
                return;
            }

            // The leaves' boxes come from the primitives' boxes in sorted order. Gathering
            // them here, in one loop of independent loads, is much cheaper than gathering
            // them in the recursion, where each leaf's load misses the cache on its own.
            bvh_.prim_ids.resize(n);
            sorted_bounds_.resize(n);
            for (size_t i = 0; i < n; ++i) {
                bvh_.prim_ids[i] = sorted[i].value;
                sorted_bounds_[i] = scene.prim_bounds[sorted[i].value];
            }
            // A binary tree over n leaves has at most 2n - 1 nodes: reserving that up front
            // means no reallocation during the build (task buffers reserve theirs likewise).
            bvh_.nodes.reserve(2 * n - 1);
            LbvhBuilder<Code> builder(sorted, sorted_bounds_, config_);
            builder.build(0, uint32_t(n), 0, bvh_.nodes, counts_, config_.threads);
        }
        bvh_.finalize(scene);
    } catch (...) {
        bvh_ = FlatBvh{};
        counts_ = {};
        throw;
    }
}

uint64_t Lbvh::reserved_bytes() const {
    auto bytes = [](const auto& v) { return uint64_t(v.capacity()) * sizeof(v[0]); };
    return bytes(bvh_.nodes) + bytes(bvh_.prim_ids) + bytes(bvh_.triangles) + bytes(sort32_.sorted) +
        bytes(sort32_.scratch) + bytes(sort64_.sorted) + bytes(sort64_.scratch) + bytes(sorted_bounds_);
}

BuildStats Lbvh::build_stats() const {
    BuildStats s = measure_bvh(bvh_);
    s.extra["morton_bits"] = config_.bits;
    s.extra["equal_code_splits"] = double(counts_.equal_code_splits);
    s.extra["forced_leaves"] = double(counts_.forced_leaves);
    if (config_.build == Build::median) s.extra["degenerate_splits"] = double(counts_.degenerate_splits);
    s.extra["build_tasks"] = double(counts_.tasks);
    s.extra["sort_passes"] = double(counts_.sort_passes);
    s.extra["sort_skipped_passes"] = double(counts_.sort_skipped_passes);
    // memory_bytes is the tree; this is everything held, build buffers and unused
    // capacity (e.g. the 2n - 1 node reservation when leaves hold several primitives).
    s.extra["reserved_bytes"] = double(reserved_bytes());
    return s;
}

template <class C>
void Lbvh::intersect(const Ray& ray, Hit& hit, C& counters) const {
    intersect_bvh(config_.traversal, bvh_, ray, hit, counters);
}

template <class C>
bool Lbvh::occluded(const Ray& ray, C& counters) const {
    return occluded_bvh(config_.traversal, bvh_, ray, counters);
}

ACCELBENCH_INSTANTIATE_RAY_QUERIES(Lbvh);

}  // namespace accelbench
