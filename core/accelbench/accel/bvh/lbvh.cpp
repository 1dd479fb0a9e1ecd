#include "accelbench/accel/bvh/lbvh.h"

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <string>
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
                   "the LBVH the report's section 5.2 measured"),
        int_param("bits", &C::bits, kMortonMinBits, kMortonMaxBits<uint64_t>,
                  "Morton grid bits per axis (2^bits cells); up to 10 sorts 32-bit codes, 11..21 64-bit codes"),
        int_param("max_prims", &C::max_prims, 1, BvhNode::kMaxLeafPrims,
                  "a range of at most this many primitives becomes a leaf (the report: 1)"),
        int_param("max_depth", &C::max_depth, 0, 1000,
                  "a node at this depth becomes a leaf whatever its size (root: depth 0; the report: 50)"),
        threads_param("threads", &C::threads, 256,
                      "build threads (0 = all cores); the tree is the same for every value"),
        int_param("task_threshold", &C::task_threshold, 1, 1e9,
                  "on several threads, a subtree is handed out as a task only above this many primitives (the report: "
                  "100)"),
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
                "optional build threads",
            .params = lbvh_params().specs(),
            .create = [](const ParamSet& p) { return std::make_unique<Lbvh>(p); },
            .label = fixed_label("LBVH"),
            .depth_limit = [](const ParamSet& p) -> std::optional<uint64_t> { return Config::from(p).max_depth; }};
}

Lbvh::Config Lbvh::Config::from(const ParamSet& p) { return lbvh_params().from(p); }

Lbvh::Lbvh(const ParamSet& params) : Lbvh(Config::from(params)) {}

Lbvh::Lbvh(const Config& config) : config_(config), threads_(config.threads) {}

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

// Builds the tree over primitives sorted by Morton code. One builder serves all tasks;
// what a task writes (its part of the node array, its counts) is passed down the recursion.
//
// On several threads, every second child of more than task_threshold primitives is handed
// out as a task (base/parallel.h). Which subtrees are handed out depends on the tree and the
// parameters alone, so the build_tasks count reported is the same for every thread count
// above one (the harness checks that builds are reproducible), and 0 on one thread, which
// hands nothing out. Where a task's nodes go:
//  - max_prims 1 (the default, the report's): every leaf holds one primitive, so a subtree
//    over m primitives has exactly 2m - 1 nodes, and a node's second child lies 2 m1 after
//    it (m1: its first child's primitives). Every task writes straight into the final array
//    at those places (`direct`), sized 2n - 1 beforehand. Only a leaf forced at max_depth
//    breaks the count; the build then starts the hierarchy again with pieces.
//  - otherwise a task builds into a piece of its own (base/tree_pieces.h), put in place
//    after its first sibling's subtree when the tree is assembled.
// Either way the array is the one a one-thread depth-first build writes.
template <class Code>
class LbvhBuilder {
public:
    // What one task writes.
    struct Output {
        BvhPiece& piece;  // direct: the whole array, shared by every task
        Lbvh::Counts& counts;
        uint32_t deepest = 0;  // deepest leaf so far (root: 0)
    };

    // `sorted_bounds[i]` is the box of the primitive sorted_[i] refers to.
    LbvhBuilder(const std::vector<KeyValue<Code>>& sorted, const std::vector<Bounds3>& sorted_bounds,
                const Lbvh::Config& config, bool parallel, bool direct)
        : sorted_(sorted), sorted_bounds_(sorted_bounds), config_(config), parallel_(parallel), direct_(direct) {}

    // Builds the subtree over sorted_[begin, end) at `depth`, its nodes in depth-first order
    // (its root first): direct, from index `pos` of the array; otherwise appended to
    // out.piece, indices relative to the piece's start. Returns the subtree's bounds. Small
    // enough to be inlined into build_inner, so that the leaves — half of all nodes — cost
    // no call of their own.
    Bounds3 build(uint32_t begin, uint32_t end, uint32_t depth, uint32_t pos, Output& out) {
        const uint32_t count = end - begin;
        if (count <= config_.max_prims || depth >= config_.max_depth) return build_leaf(begin, end, depth, pos, out);
        return build_inner(begin, end, depth, pos, out);
    }

private:
    Bounds3 build_leaf(uint32_t begin, uint32_t end, uint32_t depth, uint32_t pos, Output& out) const {
        const uint32_t count = end - begin;
        if (count > config_.max_prims) {
            if (count > BvhNode::kMaxLeafPrims)
                throw std::runtime_error("lbvh: a leaf of " + std::to_string(count) + " primitives at max_depth " +
                                         std::to_string(config_.max_depth) + " exceeds the node format's " +
                                         std::to_string(BvhNode::kMaxLeafPrims));
            ++out.counts.forced_leaves;
        }
        out.deepest = std::max(out.deepest, depth);
        const Bounds3 b = global_aabb(begin, end);
        // Direct: a forced leaf's subtree is smaller than its 2m - 1 places; the caller
        // sees forced_leaves and builds again, so nothing is written past the array.
        if (!direct_) out.piece.nodes.push_back(BvhNode::leaf(b, begin, count));
        else if (count == 1) out.piece.nodes[pos] = BvhNode::leaf(b, begin, count);
        return b;
    }

    // The box of the primitives sorted_[begin, end): the report's getGlobalAABB. A large
    // range (build=report's top nodes) in blocks on the build's threads, their boxes merged
    // in order: the same floats (base/parallel.h).
    Bounds3 global_aabb(uint32_t begin, uint32_t end) const {
        constexpr uint32_t kBlock = 1u << 15;
        if (!parallel_ || end - begin < 2 * kBlock) return global_aabb_serial(begin, end);
        std::vector<Bounds3> parts(block_count(end - begin, kBlock));
        for_blocks(true, end - begin, kBlock, [&](size_t k, size_t b, size_t e) {
            parts[k] = global_aabb_serial(begin + uint32_t(b), begin + uint32_t(e));
        });
        Bounds3 box = parts[0];
        for (size_t k = 1; k < parts.size(); ++k) box.extend(parts[k]);
        return box;
    }
    Bounds3 global_aabb_serial(uint32_t begin, uint32_t end) const {
        Bounds3 b = sorted_bounds_[begin];
        for (uint32_t i = begin + 1; i < end; ++i) b.extend(sorted_bounds_[i]);
        return b;
    }

    Bounds3 build_inner(uint32_t begin, uint32_t end, uint32_t depth, uint32_t pos, Output& out) {
        BvhNodeArray& nodes = out.piece.nodes;
        const uint32_t self = direct_ ? pos : uint32_t(nodes.size());
        if (!direct_) nodes.emplace_back();  // written once the node's box is known
        // Algorithm 2 fits the node's box from its primitives before it splits; Karras's
        // build leaves it to the children's boxes below.
        const bool report = config_.build == Lbvh::Build::report;
        const Bounds3 fitted = report ? global_aabb(begin, end) : Bounds3{};
        const Split split = report ? scan_split(begin, end) : find_split(begin, end);
        if (split.axis < 0) ++out.counts.equal_code_splits;

        Bounds3 left, right;
        uint32_t second = self + 2 * (split.index - begin);  // direct
        if (parallel_ && end - split.index > config_.task_threshold) {
            // The second child's subtree is a task of its own; this task builds the first
            // child meanwhile. Not direct: into a piece of its own, which goes in after the
            // first child's nodes (its root is index 0 of the piece, relocated on assembly).
            ++out.counts.tasks;
            std::unique_ptr<BvhPiece> piece;
            if (!direct_) {
                piece = std::make_unique<BvhPiece>();
                piece->nodes.reserve(2 * size_t(end - split.index) - 1);
            }
            Lbvh::Counts task_counts;
            Output task{direct_ ? out.piece : *piece, task_counts};
            fork_join(
                true, [&] { left = build(begin, split.index, depth + 1, self + 1, out); },
                [&] { right = build(split.index, end, depth + 1, second, task); });
            if (!direct_) {
                second = 0;
                out.piece.add_hole(self, std::move(piece));
            }
            out.counts += task_counts;
            out.deepest = std::max(out.deepest, task.deepest);
        } else {
            left = build(begin, split.index, depth + 1, self + 1, out);
            if (!direct_) second = uint32_t(nodes.size());
            right = build(split.index, end, depth + 1, second, out);
        }
        const Bounds3 b = report ? fitted : merge(left, right);
        nodes[self] = BvhNode::inner(b, second, split.axis >= 0 ? split.axis : b.largest_axis());
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

    const std::vector<KeyValue<Code>>& sorted_;
    const std::vector<Bounds3>& sorted_bounds_;
    const Lbvh::Config& config_;
    bool parallel_, direct_;
};

// The centroid bounds the codes are made over: per block, merged in order (base/parallel.h).
Bounds3 centroid_bounds(std::span<const Vec3> centroids, bool parallel) {
    constexpr size_t kBlock = 1 << 16;
    if (!parallel || centroids.size() < 2 * kBlock) return point_bounds(centroids);
    std::vector<Bounds3> parts(block_count(centroids.size(), kBlock));
    for_blocks(true, centroids.size(), kBlock, [&](size_t k, size_t begin, size_t end) {
        parts[k] = point_bounds(centroids.subspan(begin, end - begin));
    });
    Bounds3 box;
    for (const Bounds3& part : parts) box.extend(part);
    return box;
}

}  // namespace

void Lbvh::build(const Scene& scene) {
    threads_.run([&] {
        if (config_.bits <= kMortonMaxBits<uint32_t>) build_with<uint32_t>(scene);
        else build_with<uint64_t>(scene);
    });
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
    const bool parallel = threads_.parallel();
    constexpr size_t kBlock = 1 << 14;  // primitives per block of the parallel stages
    uint32_t deepest = 0;
    try {
        if (n > 0) {
            if (n > UINT32_MAX / 2) throw std::runtime_error("lbvh: scene '" + scene.name + "' has too many triangles");
            // Codes over the centroid bounds, then one sort; every stage in blocks on the
            // build's threads (Karras 2012 builds each stage in parallel).
            const MortonQuantizer quantizer(centroid_bounds(scene.centroids, parallel), config_.bits);
            sorted.resize(n);
            for_blocks(parallel, n, kBlock, [&](size_t, size_t begin, size_t end) {
                for (size_t i = begin; i < end; ++i)
                    sorted[i] = {quantizer.code<Code>(scene.centroids[i]), uint32_t(i)};
            });
            const RadixSortStats sort =
                radix_sort(sorted, buffers.scratch, 3 * config_.bits, config_.sort_digit_bits, parallel);
            counts_.sort_passes = uint64_t(sort.passes);
            counts_.sort_skipped_passes = uint64_t(sort.skipped_passes);
            if (config_.build == Build::median) {
                // The report's LBVH: after the codes and the sort, the median BVH's build
                // over the scene, so the tree is the median BVH's bit for bit.
                BvhMedianSplit median;
                BvhTopDownCounts top_down;
                bvh_ = build_bvh_top_down(scene, {config_.max_prims, config_.max_depth, BvhAxisRule::longest, parallel},
                                          median, top_down);
                counts_.forced_leaves = top_down.forced_leaves;
                counts_.degenerate_splits = top_down.degenerate_splits;
                return;
            }

            // The leaves' boxes come from the primitives' boxes in sorted order. Gathering
            // them here, in one loop of independent loads, is much cheaper than gathering
            // them in the recursion, where each leaf's load misses the cache on its own.
            bvh_.prim_ids.resize(n);
            sorted_bounds_.resize(n);
            for_blocks(parallel, n, kBlock, [&](size_t, size_t begin, size_t end) {
                for (size_t i = begin; i < end; ++i) {
                    bvh_.prim_ids[i] = sorted[i].value;
                    sorted_bounds_[i] = scene.prim_bounds[sorted[i].value];
                }
            });
            // A binary tree over n leaves has at most 2n - 1 nodes: reserving that up front
            // means no reallocation during the build (task pieces reserve theirs likewise).
            // On several threads the root's piece is small and the tree is assembled into
            // bvh_.nodes; the piece's vector is kept for the next build.
            // One thread: the nodes appended to bvh_.nodes, whose capacity a rebuild reuses.
            // Several, max_prims 1: written in place into bvh_.nodes, sized 2n - 1. Several,
            // else (or a forced leaf in place): pieces assembled into bvh_.nodes; the root
            // piece's vector is kept for the next build.
            const bool direct = parallel && config_.max_prims == 1;
            BvhPiece root;
            root.nodes.swap(direct || !parallel ? bvh_.nodes : spare_nodes_);
            root.nodes.clear();
            if (direct) root.nodes.resize(2 * n - 1);  // not written (DefaultInitAllocator)
            else if (!parallel) root.nodes.reserve(2 * n - 1);
            typename LbvhBuilder<Code>::Output out{root, counts_};
            LbvhBuilder<Code>(sorted, sorted_bounds_, config_, parallel, direct).build(0, uint32_t(n), 0, 0, out);
            if (direct && counts_.forced_leaves > 0) {
                // Some subtree has fewer than 2m - 1 nodes: again, in pieces.
                bvh_.nodes.swap(root.nodes);
                root.nodes.swap(spare_nodes_);
                root.nodes.clear();
                const Lbvh::Counts sorting = counts_;
                counts_ = {};
                counts_.sort_passes = sorting.sort_passes;
                counts_.sort_skipped_passes = sorting.sort_skipped_passes;
                out.deepest = 0;
                LbvhBuilder<Code>(sorted, sorted_bounds_, config_, parallel, false).build(0, uint32_t(n), 0, 0, out);
                assemble_bvh_pieces(root, bvh_.nodes, parallel);
                spare_nodes_.swap(root.nodes);
            } else if (direct || !parallel) {
                bvh_.nodes.swap(root.nodes);
            } else {
                assemble_bvh_pieces(root, bvh_.nodes, parallel);
                spare_nodes_.swap(root.nodes);
            }
            deepest = out.deepest;
        }
        bvh_.finalize(scene, deepest, parallel);
    } catch (...) {
        bvh_ = FlatBvh{};
        counts_ = {};
        throw;
    }
}

uint64_t Lbvh::reserved_bytes() const {
    auto bytes = [](const auto& v) { return uint64_t(v.capacity()) * sizeof(v[0]); };
    return bytes(bvh_.nodes) + bytes(bvh_.prim_ids) + bytes(bvh_.triangles) + bytes(sort32_.sorted) +
        bytes(sort32_.scratch) + bytes(sort64_.sorted) + bytes(sort64_.scratch) + bytes(sorted_bounds_) +
        bytes(spare_nodes_);
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
