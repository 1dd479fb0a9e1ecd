#include "accelbench/accel/bvh/bvh.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "accelbench/accel/bvh/bvh_metrics.h"
#include "accelbench/base/param_table.h"

namespace accelbench {

namespace {

constexpr std::array<std::string_view, 2> kAxisNames = {"longest", "round_robin"};        // BvhAxisRule's order
constexpr std::array<std::string_view, 3> kLeafTestNames = {"auto", "scalar", "packet"};  // LeafTest's order

// How tables and figures name a split (the report's words where it has them).
std::string split_label(Bvh::Split split) {
    switch (split) {
        case Bvh::Split::median: return "median";
        case Bvh::Split::midpoint: return "midpoint";
        case Bvh::Split::mean: return "mean";
        case Bvh::Split::spatial_median: return "spatial median";
        case Bvh::Split::sah: return "binned SAH";
    }
    return "?";
}

// The parameters, each once: its row and its Config member, whose initializer is the default.
const ParamTable<Bvh::Config>& bvh_params() {
    using C = Bvh::Config;
    static const ParamTable<C> rows = {
        enum_param("split", &C::split, Bvh::kSplitNames,
                   "where a node splits: object median (report default), centre of the centroid box (report's "
                   "centroid method), centroid mean, equal triangle area (spatial median), binned SAH (Wald 2007)"),
        enum_param("axis", &C::axis, kAxisNames,
                   "split axis: longest axis of the node's centroid box (report, Figure 6) or x, y, z by depth"),
        auto_int_param("max_prims", &C::max_prims, 1, BvhNode::kMaxLeafPrims,
                       "largest leaf; auto = " + std::to_string(C::default_max_prims(Bvh::Split::median)) +
                           " for the report's splits, " + std::to_string(C::default_max_prims(Bvh::Split::sah)) +
                           " for sah, which makes a leaf wherever its SAH cost is not above the best split's"),
        int_param("max_depth", &C::max_depth, 0, 1000,
                  "nodes at this depth become leaves whatever their size (report Table 3: 50)"),
        int_param("bins", &C::bins, 2, 1024, "SAH bins along the split axis (split=sah only)"),
        int_param("all_axes_min", &C::all_axes_min, 0, BvhNode::kMaxLeafPrims,
                  "split=sah only: a range of at least this many triangles takes the cheapest plane over all three "
                  "axes (Embree, bvh v2), a smaller one bins along `axis` only; 1 = every range, 0 = none"),
        float_param("traversal_cost", &C::traversal_cost, 0, 1e6, "SAH cost of visiting a node (split=sah only)"),
        float_param("isect_cost", &C::isect_cost, 1e-6, 1e6, "SAH cost of one triangle test (split=sah only)"),
        bvh_traversal_param(&C::traversal),
        enum_param("leaf_test", &C::leaf_test, kLeafTestNames,
                   "scalar: a leaf's triangles one watertight test at a time; packet: four per SSE test (the wide "
                   "BVH's), the same answers; auto: packet where a leaf may hold more than one triangle (max_prims > "
                   "1, as split=sah's default), scalar for one-triangle leaves"),
        int_param("reinsertion", &C::reinsertion, 0, 100,
                  "passes of the reinsertion optimizer after the build (Meister & Bittner 2018; 0 = off, bvh v2 "
                  "uses 3): lower SAH cost for a longer build, the same answers"),
        threads_param("threads", &C::threads, 256,
                      "build threads (0 = all cores); the tree is the same for every value"),
    };
    return rows;
}

}  // namespace

AcceleratorInfo Bvh::info() {
    return {.name = "bvh",
            .description =
                "top-down BVH (report section 2): fit & split with median/midpoint/mean/spatial-median or "
                "binned SAH splits, flattened depth-first; optional reinsertion optimizer",
            .params = bvh_params().specs(),
            .create = [](const ParamSet& p) { return std::make_unique<Bvh>(p); },
            .label = [](const ParamSet& p) { return "BVH (" + split_label(Config::from(p).split) + ")"; },
            .depth_limit = [](const ParamSet& p) -> std::optional<uint64_t> { return Config::from(p).max_depth; }};
}

Bvh::Config Bvh::Config::from(const ParamSet& p) { return bvh_params().from(p); }

namespace {

// Moves the references whose centroid lies below `plane` on `axis` to the front; no
// split when that leaves a side empty.
std::optional<BvhSplit> partition_at(std::span<BvhPrimRef> refs, int axis, float plane) {
    const size_t mid = with_axis(axis, [&](auto a) {
        return size_t(std::partition(refs.begin(), refs.end(),
                                     [a, plane](const BvhPrimRef& r) { return r.centroid(a) < plane; }) -
                      refs.begin());
    });
    if (mid == 0 || mid == refs.size()) return std::nullopt;
    return BvhSplit{mid, axis};
}

// The report's centroid method (equation 1): cut the node's centroid box in half. Adapts
// to the distribution (sparse regions are cut off quickly) but gives unbalanced trees on
// clustered input.
struct MidpointSplit {
    std::optional<BvhSplit> operator()(std::span<BvhPrimRef> refs, const BvhSplitRequest& r) const {
        const float plane = 0.5f * (r.centroid_bounds.lower[r.axis] + r.centroid_bounds.upper[r.axis]);
        return partition_at(refs, r.axis, plane);
    }
};

// Object mean: the plane at the mean centroid (the report's example {1,3,3,6,7,8,9}:
// mean 5.29, left {1,3,3}).
struct MeanSplit {
    std::optional<BvhSplit> operator()(std::span<BvhPrimRef> refs, const BvhSplitRequest& r) const {
        const double sum = with_axis(r.axis, [&](auto a) {
            double acc = 0;  // double: millions of floats
            for (const BvhPrimRef& ref : refs) acc += ref.centroid(a);
            return acc;
        });
        return partition_at(refs, r.axis, float(sum / double(refs.size())));
    }
};

// Spatial median (report 2.2.1, Figure 5c): order the primitives along the axis and cut
// where the triangle areas on the two sides are closest to equal, so one large triangle
// can balance many small ones. Sorting makes it O(n log n) per node.
class SpatialMedianSplit {
public:
    // The areas are shared by the copies the build's tasks make.
    explicit SpatialMedianSplit(const Scene& scene) {
        auto area = std::make_shared<std::vector<double>>(scene.triangle_count());
        for (size_t i = 0; i < area->size(); ++i) {
            const Vec3 p0 = scene.vertex(uint32_t(i), 0);
            (*area)[i] =
                0.5 * double(length(cross(scene.vertex(uint32_t(i), 1) - p0, scene.vertex(uint32_t(i), 2) - p0)));
        }
        area_ = std::move(area);
    }

    std::optional<BvhSplit> operator()(std::span<BvhPrimRef> refs, const BvhSplitRequest& r) const {
        with_axis(r.axis, [&](auto a) {
            std::sort(refs.begin(), refs.end(),
                      [a](const BvhPrimRef& x, const BvhPrimRef& y) { return x.centroid(a) < y.centroid(a); });
        });
        const std::vector<double>& area = *area_;
        double total = 0;
        for (const BvhPrimRef& ref : refs) total += area[ref.id];
        if (!(total > 0)) return std::nullopt;  // only degenerate triangles: no area to halve
        const double half = 0.5 * total;
        double left = 0, best_gap = kInfinity;
        size_t best = 0;
        for (size_t mid = 1; mid < refs.size(); ++mid) {
            left += area[refs[mid - 1].id];
            const double gap = std::fabs(left - half);
            if (gap < best_gap) {
                best_gap = gap;
                best = mid;
            }
        }
        return BvhSplit{best, r.axis};
    }

private:
    std::shared_ptr<const std::vector<double>> area_;  // per scene triangle
};

// The binned SAH's parts (SahSplit below): lanes x, y, z and a fourth never read back.
using F4 = BvhBoxAccumulator::F4;
using I4 = int32_t __attribute__((vector_size(16)));
constexpr F4 kInf4 = {kInfinity, kInfinity, kInfinity, kInfinity};

// Centroid -> bin, along each axis (lanes 0-2): (c - lo) * scale clamped to [0, K - 1].
// Clamped in float before the conversion: a tiny extent can make scale infinite, and
// (c - lo) * scale then infinite (clamped to K - 1) or, at c = lo, NaN (sent to bin 0,
// NaN failing the first comparison). An axis without extent (no
// plane; the builder never asks for one when its own axis has none) gets scale 0, not a
// division by zero: every centroid in bin 0. Lane 3 maps everything to bin 0.
struct SahBinMap {
    F4 lo, scale, last;
    SahBinMap(const BvhSplitRequest& r, uint32_t bins) {
        const Bounds3& cb = r.centroid_bounds;
        // (1 - 1e-6): the largest centroid lands in the last bin, not one past it.
        const float k = float(bins) * (1.0f - 1e-6f);
        auto scale_of = [k](float lower, float upper) { return upper > lower ? k / (upper - lower) : 0.0f; };
        lo = F4{cb.lower.x, cb.lower.y, cb.lower.z, 0.0f};
        scale = F4{scale_of(cb.lower.x, cb.upper.x), scale_of(cb.lower.y, cb.upper.y), scale_of(cb.lower.z, cb.upper.z),
                   0.0f};
        const float l = float(bins - 1);
        last = F4{l, l, l, 0.0f};
    }
    I4 bins(F4 centroid) const {
        F4 f = (centroid - lo) * scale;
        const F4 zero = {};
        f = zero < f ? f : zero;  // NaN -> 0
        f = f < last ? f : last;
        return __builtin_convertvector(f, I4);
    }
};

// A candidate plane of the binned SAH and what its sweep knows of the two sides.
struct SahPlane {
    float sum = kInfinity;  // A_left N_left + A_right N_right
    uint32_t plane = 0;     // 0: none
    uint32_t left_count = 0;
    BvhBoxAccumulator left, right;  // the two sides' boxes
};

// The children's centroid boxes of a binned SAH split, taken while moving references to
// their sides (SahSplit::partition).
struct SahSides {
    F4 lo[2] = {kInf4, kInf4}, hi[2] = {-kInf4, -kInf4};

    // Moves refs to scratch, the left ones from `left` on, the right ones from `right`
    // on; returns where each side ended.
    std::pair<size_t, size_t> move(std::span<const BvhPrimRef> refs, std::span<BvhPrimRef> scratch,
                                   const SahBinMap& map, int axis, uint32_t plane, size_t left, size_t right) {
        switch (axis) {
            case 0: return move_along<0>(refs.data(), refs.size(), scratch.data(), map, plane, left, right);
            case 1: return move_along<1>(refs.data(), refs.size(), scratch.data(), map, plane, left, right);
            default: return move_along<2>(refs.data(), refs.size(), scratch.data(), map, plane, left, right);
        }
    }
    // The loop, every value it updates a local (not a capture or a member, which each store
    // of a reference would make the compiler reload and store: it cannot tell they do not
    // alias). Written as the one-thread partition was, where GCC 12 selects the
    // destination with cmov; in other forms it made `is_right ? right : left` a branch,
    // taken as the data says (0.26M more mispredictions per bunny build, 20% more time).
    template <int A>
    std::pair<size_t, size_t> move_along(const BvhPrimRef* refs, size_t n, BvhPrimRef* out, const SahBinMap& map,
                                         uint32_t plane, size_t left, size_t right) {
        F4 l[2] = {lo[0], lo[1]}, h[2] = {hi[0], hi[1]};
        const std::span<BvhPrimRef> scratch(out, right + n);
        for (const BvhPrimRef& ref : std::span<const BvhPrimRef>(refs, n)) {
            const F4 c = BvhBoxAccumulator::centroid(ref);
            const bool is_right = uint32_t(map.bins(c)[A]) >= plane;
            scratch[is_right ? right : left] = ref;
            left += !is_right;
            right += is_right;
            const I4 m = I4{} - int32_t(is_right);  // all ones on the right
            l[0] = m ? l[0] : (c < l[0] ? c : l[0]);
            h[0] = m ? h[0] : (c > h[0] ? c : h[0]);
            l[1] = m ? (c < l[1] ? c : l[1]) : l[1];
            h[1] = m ? (c > h[1] ? c : h[1]) : h[1];
        }
        for (int k = 0; k < 2; ++k) {
            lo[k] = l[k];
            hi[k] = h[k];
        }
        return {left, right};
    }
    // Merges the boxes of references that came after this one's (the earlier's lanes win
    // ties, as in one pass).
    void add(const SahSides& o) {
        for (int k = 0; k < 2; ++k) {
            lo[k] = o.lo[k] < lo[k] ? o.lo[k] : lo[k];
            hi[k] = o.hi[k] > hi[k] ? o.hi[k] : hi[k];
        }
    }
    BvhSplit split(int axis, const SahPlane& best) const {
        BvhSplit s{best.left_count, axis, /*in_scratch=*/true, /*fitted=*/true};
        s.bounds[0] = best.left.bounds();
        s.bounds[1] = best.right.bounds();
        for (int k = 0; k < 2; ++k)
            s.centroid_bounds[k] = {{lo[k][0], lo[k][1], lo[k][2]}, {hi[k][0], hi[k][1], hi[k][2]}};
        return s;
    }
};

// Binned SAH (Wald 2007): instead of sorting, drop each centroid into one of K equal
// bins along the axis (O(n)) — along all three axes in ranges of all_axes_min or more
// references (bvh.h) — keep each bin's box and count, and evaluate the SAH
//   cost(plane) = C_trav * A + C_isect * (A_left * N_left + A_right * N_right)
// (the usual cost multiplied by the node's area A, so a flat node needs no division) at
// the K-1 bin boundaries of each axis with two sweeps over its bins. Like pbrt-v4's BVH
// build, a range small enough to be a leaf (<= max_prims) stays a leaf when that is cheaper
// (C_isect * N * A). The range is then partitioned out of place, the children's boxes taken
// from the bins and their centroid boxes on the way (partition() below), so the builder
// reads the references once for the bins and once to move them, and never to fit them.
// Measured (accel_bench, build / Embree, three rounds, all_axes_min 1024) against
// std::partition in place and the builder's fit of both children: bunny 0.71-0.74 ->
// 0.52-0.54, dragon 0.82-0.85 -> 0.72-0.78, conference 0.68-0.72 -> 0.73-0.74 (slower there,
// not analysed; every reference is copied, where std::partition moves only those out of place).
// (Embree's block form of the counts, ceil(N / 4): measured and not adopted, docs/decisions.md.)
class SahSplit {
public:
    static constexpr bool kMayStopEarly = true;

    // all_axes_min: in a range of at least this many references the planes of all three
    // axes compete (as in Embree's and bvh v2's binned builders), in smaller ones only those
    // of the axis rule's axis (as in pbrt-v4's); 0: the axis rule's everywhere.
    SahSplit(uint32_t bins, float traversal_cost, float isect_cost, uint32_t all_axes_min)
        : bins_(bins),
          words_((size_t(bins) + 63) / 64),
          traversal_cost_(traversal_cost),
          isect_cost_(isect_cost),
          all_axes_min_(all_axes_min),
          bin_bounds_(3 * size_t(bins)),
          bin_counts_(3 * size_t(bins)),
          right_bounds_(bins),
          right_count_(bins),
          used_(3 * words_) {}

    std::optional<BvhSplit> operator()(std::span<BvhPrimRef> refs, const BvhSplitRequest& r) {
        const SahBinMap map(r, bins_);
        const bool all_axes = all_axes_min_ > 0 && refs.size() >= all_axes_min_;
        std::vector<BlockBins> blocks;  // r.parallel: each block's bins
        if (r.parallel) bin_blocks(refs, map, r.axis, all_axes, blocks);
        else if (all_axes) bin<true>(refs, map, r.axis);
        else bin<false>(refs, map, r.axis);
        // The cheapest plane; of equally cheap ones the first in x, y, z order. An axis the
        // centroids do not spread along has no plane (all of them in one bin); its bins are
        // still emptied.
        int best_axis = r.axis;
        SahPlane best;
        for (int axis = 0; axis < 3; ++axis) {
            if (!all_axes && axis != r.axis) continue;
            if (const SahPlane p = best_plane_on(axis); p.sum < best.sum) {
                best = p;
                best_axis = axis;
            }
        }
        if (best.plane == 0) return std::nullopt;
        const float node_area = r.bounds.area();
        if (r.leaf_allowed &&
            isect_cost_ * float(refs.size()) * node_area <= traversal_cost_ * node_area + isect_cost_ * best.sum)
            return std::nullopt;
        return r.parallel ? partition_blocks(refs, r.scratch, map, best_axis, best, blocks)
                          : partition(refs, r.scratch, map, best_axis, best);
    }

private:
    // Moves the references below `best`'s plane to scratch[0, left_count) and the others to
    // scratch[left_count, n), each side in its order, without a branch on the side, and
    // takes the children's centroid boxes on the way. Their boxes come from the bins (the
    // same unions of the same boxes as a fit, so the same floats), so the builder does not
    // read the references again. The side is decided by the binning's own arithmetic
    // (SahBinMap::bins), so every reference goes where the sweep counted it.
    BvhSplit partition(std::span<const BvhPrimRef> refs, std::span<BvhPrimRef> scratch, const SahBinMap& map, int axis,
                       const SahPlane& best) const {
        SahSides sides;
        const auto [left, right] = sides.move(refs, scratch, map, axis, best.plane, 0, best.left_count);
        // The sweep counted the sides with the same SahBinMap::bins, so this cannot fail unless
        // that arithmetic stopped being deterministic (it is compiled without contraction).
        if (left != best.left_count || right != refs.size())
            throw std::logic_error("bvh: SAH partition disagrees with its bins");
        return sides.split(axis, best);
    }

    // One block's bins of a range split on the build's threads: per axis (axis * bins_ + bin).
    struct BlockBins {
        std::vector<BvhBoxAccumulator> bounds;
        std::vector<uint32_t> counts;
    };
    static constexpr size_t kBlock = 1 << 14;  // references per block

    // bin() for a large range on the build's threads: each block into its own bins, merged in
    // order into the strategy's (a bin's box the same union as in one pass, base/parallel.h).
    void bin_blocks(std::span<const BvhPrimRef> refs, const SahBinMap& map, int axis, bool all_axes,
                    std::vector<BlockBins>& blocks) {
        const size_t per_block = 3 * size_t(bins_);
        blocks.resize(block_count(refs.size(), kBlock));
        for_blocks(true, refs.size(), kBlock, [&](size_t k, size_t begin, size_t end) {
            BlockBins& bb = blocks[k];
            bb.bounds.assign(per_block, BvhBoxAccumulator{});
            bb.counts.assign(per_block, 0);
            for (size_t i = begin; i < end; ++i) {
                const BvhPrimRef& ref = refs[i];
                const I4 b = map.bins(BvhBoxAccumulator::centroid(ref));
                for (int a = all_axes ? 0 : axis; a < (all_axes ? 3 : axis + 1); ++a) {
                    const size_t j = size_t(a) * bins_ + uint32_t(b[a]);
                    bb.bounds[j].extend(ref);
                    ++bb.counts[j];
                }
            }
        });
        for (const BlockBins& bb : blocks)
            for (size_t j = 0; j < per_block; ++j) {
                bin_bounds_[j].extend(bb.bounds[j]);
                bin_counts_[j] += bb.counts[j];
            }
        for (int a = 0; a < 3; ++a) {
            uint64_t* const words = &used_[size_t(a) * words_];
            if (words_ == 1) {
                words[0] = 0;
                for (uint32_t b = 0; b < bins_; ++b) words[0] |= uint64_t(bin_counts_[size_t(a) * bins_ + b] > 0) << b;
                continue;
            }
            std::fill_n(words, words_, ~uint64_t(0));
            if (bins_ % 64) words[words_ - 1] = (uint64_t(1) << (bins_ % 64)) - 1;
        }
    }

    // partition() for a large range on the build's threads: each block moves its references
    // to where the blocks before it end, on either side (the per-block counts of the bins
    // below the plane say how many go left).
    BvhSplit partition_blocks(std::span<const BvhPrimRef> refs, std::span<BvhPrimRef> scratch, const SahBinMap& map,
                              int axis, const SahPlane& best, const std::vector<BlockBins>& blocks) const {
        std::vector<std::pair<size_t, size_t>> starts(blocks.size());
        size_t left = 0, right = best.left_count;
        for (size_t k = 0; k < blocks.size(); ++k) {
            starts[k] = {left, right};
            const uint32_t* counts = &blocks[k].counts[size_t(axis) * bins_];
            const size_t block_refs = std::min(refs.size(), (k + 1) * kBlock) - k * kBlock;
            size_t block_left = 0;
            for (uint32_t b = 0; b < best.plane; ++b) block_left += counts[b];
            left += block_left;
            right += block_refs - block_left;
        }
        if (left != best.left_count || right != refs.size())
            throw std::logic_error("bvh: SAH partition disagrees with its bins");
        std::vector<SahSides> sides(blocks.size());
        for_blocks(true, refs.size(), kBlock, [&](size_t k, size_t begin, size_t end) {
            const auto [l, r] = sides[k].move(refs.subspan(begin, end - begin), scratch, map, axis, best.plane,
                                              starts[k].first, starts[k].second);
            const bool last = k + 1 == blocks.size();
            if (l != (last ? best.left_count : starts[k + 1].first) || r != (last ? refs.size() : starts[k + 1].second))
                throw std::logic_error("bvh: SAH partition disagrees with its bins");
        });
        for (size_t k = 1; k < sides.size(); ++k) sides[0].add(sides[k]);
        return sides[0].split(axis, best);
    }

    // Drops every reference into its bin along all three axes (kAll: one pass computes the
    // three bins at once, as Embree's binner does) or along `axis` alone. The bins are empty
    // on entry (emptied by best_plane_on).
    template <bool kAll>
    void bin(std::span<const BvhPrimRef> refs, const SahBinMap& map, int axis) {
        BvhBoxAccumulator* const bounds = bin_bounds_.data();
        uint32_t* const counts = bin_counts_.data();
        // Which bins are used, kept in registers where one word holds an axis's bins (up to
        // 64 bins; 32 is the default). With more bins every bin counts as used: an empty bin's
        // plane repeats the one before it, which it cannot beat, so only the sweeps' length
        // changes, not their answer.
        uint64_t used[3] = {};
        for (const BvhPrimRef& ref : refs) {
            const I4 b = map.bins(BvhBoxAccumulator::centroid(ref));
            for (int a = kAll ? 0 : axis; a < (kAll ? 3 : axis + 1); ++a) {
                const size_t i = size_t(a) * bins_ + uint32_t(b[a]);
                bounds[i].extend(ref);
                ++counts[i];
                used[a] |= uint64_t(1) << (b[a] & 63);
            }
        }
        for (int a = 0; a < 3; ++a) {
            if (words_ == 1) {
                used_[a] = used[a];
                continue;
            }
            uint64_t* const words = &used_[size_t(a) * words_];
            std::fill_n(words, words_, ~uint64_t(0));
            if (bins_ % 64) words[words_ - 1] = (uint64_t(1) << (bins_ % 64)) - 1;  // no bits past the last bin
        }
    }

    // The cheapest bin boundary along `axis`; leaves that axis's bins empty.
    SahPlane best_plane_on(int axis) {
        BvhBoxAccumulator* const bounds = &bin_bounds_[size_t(axis) * bins_];
        uint32_t* const counts = &bin_counts_[size_t(axis) * bins_];
        uint64_t* const used = &used_[size_t(axis) * words_];
        // The sweeps visit the non-empty bins only (`used_`, a bit per bin): most of a small
        // range's bins are empty, and looping over all of them was a fifth of the build's
        // instructions at 32 bins. The planes, sums and their order are those of a sweep
        // over every bin, so the tree is the same.
        //
        // Right sweep: for plane i = b + 1 after a non-empty bin b (the only planes the left
        // sweep evaluates), the box area and count of bins [i, K).
        BvhBoxAccumulator acc;
        uint32_t count = 0;
        for (size_t w = words_; w-- > 0;)
            for (uint64_t bits = used[w]; bits; bits &= ~(uint64_t(1) << (63 - std::countl_zero(bits)))) {
                const uint32_t b = uint32_t(w * 64 + size_t(63 - std::countl_zero(bits)));
                if (b + 1 < bins_) {
                    right_bounds_[b + 1] = acc;
                    right_count_[b + 1] = count;
                }
                acc.extend(bounds[b]);
                count += counts[b];
            }
        // Left sweep: plane i = b + 1 separates bins [0, i) from [i, K). After an empty bin
        // the partition equals the previous plane's, so it cannot cost strictly less: only
        // planes after a non-empty bin.
        // Planes are compared by their area-weighted counts alone, A_left N_left + A_right
        // N_right: the term C_trav A is the same for every plane, and adding it before the
        // comparison let its rounding decide near ties, so the planes chosen moved with
        // traversal_cost (Tables 4 and 5's max_prims=1 trees differed in a few nodes between
        // traversal_cost 1 and 4). The costs enter the leaf decision only.
        SahPlane best;
        acc = BvhBoxAccumulator{};
        count = 0;
        for (size_t w = 0; w < words_; ++w) {
            for (uint64_t bits = used[w]; bits; bits &= bits - 1) {
                const uint32_t b = uint32_t(w * 64 + size_t(std::countr_zero(bits)));
                acc.extend(bounds[b]);
                count += counts[b];
                counts[b] = 0;  // the bins are left empty for the next range
                bounds[b] = BvhBoxAccumulator{};
                const uint32_t i = b + 1;
                if (i >= bins_ || count == 0 || right_count_[i] == 0) continue;
                const float sum = acc.area() * float(count) + right_bounds_[i].area() * float(right_count_[i]);
                if (sum < best.sum) best = {sum, i, count, acc, right_bounds_[i]};
            }
            used[w] = 0;
        }
        return best;
    }

    uint32_t bins_;
    size_t words_;  // of used_, per axis
    float traversal_cost_, isect_cost_;
    uint32_t all_axes_min_;
    // Per axis (axis * bins_ + bin), allocated once per build and reused by every node.
    std::vector<BvhBoxAccumulator> bin_bounds_;
    std::vector<uint32_t> bin_counts_;
    std::vector<BvhBoxAccumulator> right_bounds_;  // of bins [i, K), for plane i
    std::vector<uint32_t> right_count_;
    std::vector<uint64_t> used_;  // per axis (axis * words_ + word), bit b: bin b is not empty
};

}  // namespace

Bvh::Bvh(const ParamSet& params) : Bvh(Config::from(params)) {}

Bvh::Bvh(const Config& config) : config_(config), threads_(config.threads) {}

void Bvh::build(const Scene& scene) {
    threads_.run([&] { build_on_threads(scene); });
}

void Bvh::build_on_threads(const Scene& scene) {
    const BvhTopDownSettings settings{config_.leaf_limit(), config_.max_depth, config_.axis, threads_.parallel()};
    auto build_with = [&](auto&& strategy) { bvh_ = build_bvh_top_down(scene, settings, strategy, counts_); };
    switch (config_.split) {
        case Split::median: build_with(BvhMedianSplit{}); break;
        case Split::midpoint: build_with(MidpointSplit{}); break;
        case Split::mean: build_with(MeanSplit{}); break;
        case Split::spatial_median: build_with(SpatialMedianSplit(scene)); break;
        case Split::sah:
            build_with(SahSplit(config_.bins, config_.traversal_cost, config_.isect_cost, config_.all_axes_min));
            break;
    }
    reinsertion_counts_ = optimize_bvh_by_reinsertion(bvh_, scene, {config_.reinsertion});
    if (config_.packet_leaves()) {
        packets_.build(bvh_, threads_.parallel());
        // The packets hold the same vertices; the slot copies only the scalar test reads
        // would double the memory the structure holds and reports (bunny: 6.9 MB, 4.4 without).
        bvh_.triangles = {};
    } else {
        packets_ = {};
    }
}

BuildStats Bvh::build_stats() const {
    BuildStats s = measure_bvh(bvh_);
    if (s.memory_bytes) *s.memory_bytes += packets_.memory_bytes();
    s.extra["degenerate_splits"] = double(counts_.degenerate_splits);
    s.extra["forced_leaves"] = double(counts_.forced_leaves);
    if (config_.reinsertion > 0) s.extra["reinsertions"] = double(reinsertion_counts_.reinsertions);
    return s;
}

template <class C>
void Bvh::intersect(const Ray& ray, Hit& hit, C& counters) const {
    if (config_.packet_leaves()) intersect_bvh<PacketLeafTest>(config_.traversal, bvh_, packets_, ray, hit, counters);
    else intersect_bvh(config_.traversal, bvh_, ray, hit, counters);
}

template <class C>
bool Bvh::occluded(const Ray& ray, C& counters) const {
    if (config_.packet_leaves()) return occluded_bvh<PacketLeafTest>(config_.traversal, bvh_, packets_, ray, counters);
    return occluded_bvh(config_.traversal, bvh_, ray, counters);
}

ACCELBENCH_INSTANTIATE_RAY_QUERIES(Bvh);

}  // namespace accelbench
