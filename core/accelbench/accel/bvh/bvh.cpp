#include "accelbench/accel/bvh/bvh.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "accelbench/accel/bvh/bvh_metrics.h"

namespace accelbench {

namespace {

constexpr std::array<std::string_view, 2> kAxisNames = {"longest", "round_robin"};  // BvhAxisRule's order

// The index of `name` in `names` (the ParamSet has checked that it is one of them).
template <size_t N>
size_t index_of(const std::array<std::string_view, N>& names, const std::string& name) {
    return size_t(std::find(names.begin(), names.end(), name) - names.begin()) % N;
}

template <size_t N>
std::vector<std::string> choices(const std::array<std::string_view, N>& names) {
    return {names.begin(), names.end()};
}

}  // namespace

AcceleratorInfo Bvh::info() {
    const Config d;  // the defaults
    return {"bvh",
            "top-down BVH (report section 2): fit & split with median/midpoint/mean/spatial-median or binned SAH "
            "splits, flattened depth-first; optional reinsertion optimizer",
            {
                {"split", ParamType::Enum, std::string(kSplitNames[size_t(d.split)]), choices(kSplitNames), 0, 0,
                 "where a node splits: object median (report default), centre of the centroid box (report's "
                 "centroid method), centroid mean, equal triangle area (spatial median), binned SAH (Wald 2007)"},
                {"axis", ParamType::Enum, std::string(kAxisNames[size_t(d.axis)]), choices(kAxisNames), 0, 0,
                 "split axis: longest axis of the node's centroid box (report, Figure 6) or x, y, z by depth"},
                {"max_prims",
                 ParamType::Int,
                 "auto",
                 {},
                 1,
                 BvhNode::kMaxLeafPrims,
                 "largest leaf; auto = " + std::to_string(Config::default_max_prims(Split::median)) +
                     " for the report's splits, " + std::to_string(Config::default_max_prims(Split::sah)) +
                     " for sah, which makes a leaf wherever its SAH cost is not above the best split's",
                 true},
                {"max_depth",
                 ParamType::Int,
                 format_param(int64_t(d.max_depth)),
                 {},
                 0,
                 1000,
                 "nodes at this depth become leaves whatever their size (report Table 3: 50)"},
                {"bins",
                 ParamType::Int,
                 format_param(int64_t(d.bins)),
                 {},
                 2,
                 1024,
                 "SAH bins along the split axis (split=sah only)"},
                {"traversal_cost",
                 ParamType::Float,
                 format_param(double(d.traversal_cost)),
                 {},
                 0,
                 1e6,
                 "SAH cost of visiting a node (split=sah only)"},
                {"isect_cost",
                 ParamType::Float,
                 format_param(double(d.isect_cost)),
                 {},
                 1e-6,
                 1e6,
                 "SAH cost of one triangle test (split=sah only)"},
                bvh_traversal_param(),
                {"leaf_test",
                 ParamType::Enum,
                 "auto",
                 {"auto", "scalar", "packet"},
                 0,
                 0,
                 "scalar: a leaf's triangles one watertight test at a time; packet: four per SSE test (the wide "
                 "BVH's), the same answers; auto: packet where a leaf may hold more than one triangle (max_prims > 1, "
                 "as split=sah's default), scalar for one-triangle leaves"},
                {"reinsertion",
                 ParamType::Int,
                 format_param(int64_t(d.reinsertion)),
                 {},
                 0,
                 100,
                 "passes of the reinsertion optimizer after the build (Meister & Bittner 2018; 0 = off, bvh v2 "
                 "uses 3): lower SAH cost for a longer build, the same answers"},
            },
            [](const ParamSet& p) { return std::make_unique<Bvh>(p); }};
}

Bvh::Config Bvh::Config::from(const ParamSet& p) {
    Config c;
    c.split = Split(index_of(kSplitNames, p.get_enum("split")));
    c.axis = BvhAxisRule(index_of(kAxisNames, p.get_enum("axis")));
    if (p.given("max_prims")) c.max_prims = uint32_t(p.get_int("max_prims"));
    c.max_depth = uint32_t(p.get_int("max_depth"));
    c.bins = uint32_t(p.get_int("bins"));
    c.traversal_cost = float(p.get_float("traversal_cost"));
    c.isect_cost = float(p.get_float("isect_cost"));
    c.traversal = bvh_traversal_from(p);
    c.reinsertion = uint32_t(p.get_int("reinsertion"));
    const std::string& leaf_test = p.get_enum("leaf_test");
    c.leaf_test = leaf_test == "scalar" ? Config::LeafTest::scalar
        : leaf_test == "packet"         ? Config::LeafTest::packet
                                        : Config::LeafTest::automatic;
    return c;
}

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

// Object median (report 2.2.1): half the primitives on each side, by centroid order.
// Balanced by construction, blind to the primitives' sizes and to empty space.
struct MedianSplit {
    using Ref = BvhCentroidRef;  // the median looks at centroids only
    std::optional<BvhSplit> operator()(std::span<Ref> refs, const BvhRangeRequest<Ref>& r) {
        return equal_counts(refs, r.scratch, r.axis, r.centroid_bounds.lower[r.axis], r.centroid_bounds.upper[r.axis]);
    }
    detail::EqualCountSplitter<Ref> equal_counts;
};

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
    explicit SpatialMedianSplit(const Scene& scene) : area_(scene.triangle_count()) {
        for (size_t i = 0; i < area_.size(); ++i) {
            const Vec3 p0 = scene.vertex(uint32_t(i), 0);
            area_[i] =
                0.5 * double(length(cross(scene.vertex(uint32_t(i), 1) - p0, scene.vertex(uint32_t(i), 2) - p0)));
        }
    }

    std::optional<BvhSplit> operator()(std::span<BvhPrimRef> refs, const BvhSplitRequest& r) const {
        with_axis(r.axis, [&](auto a) {
            std::sort(refs.begin(), refs.end(),
                      [a](const BvhPrimRef& x, const BvhPrimRef& y) { return x.centroid(a) < y.centroid(a); });
        });
        double total = 0;
        for (const BvhPrimRef& ref : refs) total += area_[ref.id];
        if (!(total > 0)) return std::nullopt;  // only degenerate triangles: no area to halve
        const double half = 0.5 * total;
        double left = 0, best_gap = kInfinity;
        size_t best = 0;
        for (size_t mid = 1; mid < refs.size(); ++mid) {
            left += area_[refs[mid - 1].id];
            const double gap = std::fabs(left - half);
            if (gap < best_gap) {
                best_gap = gap;
                best = mid;
            }
        }
        return BvhSplit{best, r.axis};
    }

private:
    std::vector<double> area_;  // per scene triangle
};

// Binned SAH (Wald 2007): instead of sorting, drop each centroid into one of K equal
// bins along the axis (O(n)), keep each bin's box and count, and evaluate the SAH
//   cost(plane) = C_trav * A + C_isect * (A_left * N_left + A_right * N_right)
// (the usual cost multiplied by the node's area A, so a flat node needs no division) at
// the K-1 bin boundaries with two sweeps over the bins. Like pbrt-v4's BVH build, a range
// small enough to be a leaf (<= max_prims) stays a leaf when that is cheaper
// (C_isect * N * A).
// Measured (session 11) and not adopted: Embree's block form of the counts, ceil(N / 4) for
// N (a leaf costs its packet tests, bvh_packet_leaves.h), with traversal_cost 0.5-2 in place
// of 4. At 2 (leaves of 6.4 triangles on the bunny) trace / Embree, interleaved with today's
// default, five rounds (the bunny two): conference 1.79-2.06 against 1.92-2.12, dragon 1.44-1.64 against
// 1.60-1.67, igea and the bunny level (1.52-1.62, 1.39-1.51 against 1.51-1.64, 1.36-1.46):
// about 3% on two models, inside the noise, for a second cost model to explain.
class SahSplit {
public:
    static constexpr bool kMayStopEarly = true;

    SahSplit(uint32_t bins, float traversal_cost, float isect_cost)
        : bins_(bins),
          traversal_cost_(traversal_cost),
          isect_cost_(isect_cost),
          bin_bounds_(bins),
          bin_counts_(bins),
          right_area_(bins),
          right_count_(bins),
          used_((size_t(bins) + 63) / 64) {}

    std::optional<BvhSplit> operator()(std::span<BvhPrimRef> refs, const BvhSplitRequest& r) {
        const int axis = r.axis;
        const float lo = r.centroid_bounds.lower[axis];
        // (1 - 1e-6): the largest centroid lands in the last bin, not one past it.
        const float scale = float(bins_) * (1.0f - 1e-6f) / (r.centroid_bounds.upper[axis] - lo);
        const uint32_t last = bins_ - 1;
        // Clamped in float before the conversion: a tiny extent can make scale infinite.
        auto bin_of = [=](const BvhPrimRef& ref, auto a) {
            return uint32_t(std::min(float(last), std::max(0.0f, (ref.centroid(a) - lo) * scale)));
        };
        // The bins are empty on entry (cleared after use below).
        with_axis(axis, [&](auto a) {
            for (const BvhPrimRef& ref : refs) {
                const uint32_t b = bin_of(ref, a);
                bin_bounds_[b].extend(ref);
                ++bin_counts_[b];
                used_[b >> 6] |= uint64_t(1) << (b & 63);
            }
        });
        // The sweeps visit the non-empty bins only (`used_`, a bit per bin): most of a small
        // range's bins are empty, and looping over all of them was a fifth of the build's
        // instructions at 32 bins. The planes, sums and their order are those of a sweep
        // over every bin, so the tree is the same.
        //
        // Right sweep: for plane i = b + 1 after a non-empty bin b (the only planes the left
        // sweep evaluates), the box area and count of bins [i, K).
        BvhBoxAccumulator acc;
        uint32_t count = 0;
        for (size_t w = used_.size(); w-- > 0;)
            for (uint64_t bits = used_[w]; bits; bits &= ~(uint64_t(1) << (63 - std::countl_zero(bits)))) {
                const uint32_t b = uint32_t(w * 64 + size_t(63 - std::countl_zero(bits)));
                if (b + 1 < bins_) {
                    right_area_[b + 1] = acc.area();
                    right_count_[b + 1] = count;
                }
                acc.extend(bin_bounds_[b]);
                count += bin_counts_[b];
            }
        // Left sweep: plane i = b + 1 separates bins [0, i) from [i, K). After an empty bin
        // the partition equals the previous plane's, so it cannot cost strictly less: only
        // planes after a non-empty bin.
        // Planes are compared by their area-weighted counts alone, A_left N_left + A_right
        // N_right: the term C_trav A is the same for every plane, and adding it before the
        // comparison let its rounding decide near ties, so the planes chosen moved with
        // traversal_cost (Tables 4 and 5's max_prims=1 trees differed in a few nodes between
        // traversal_cost 1 and 4). The costs enter the leaf decision only.
        const float node_area = r.bounds.area();
        float best_sum = kInfinity;
        uint32_t best_plane = 0;
        acc = BvhBoxAccumulator{};
        count = 0;
        for (size_t w = 0; w < used_.size(); ++w) {
            for (uint64_t bits = used_[w]; bits; bits &= bits - 1) {
                const uint32_t b = uint32_t(w * 64 + size_t(std::countr_zero(bits)));
                acc.extend(bin_bounds_[b]);
                count += bin_counts_[b];
                bin_counts_[b] = 0;  // the bins are left empty for the next range
                bin_bounds_[b] = BvhBoxAccumulator{};
                const uint32_t i = b + 1;
                if (i >= bins_ || right_count_[i] == 0) continue;
                const float sum = acc.area() * float(count) + right_area_[i] * float(right_count_[i]);
                if (sum < best_sum) {
                    best_sum = sum;
                    best_plane = i;
                }
            }
            used_[w] = 0;
        }
        if (best_plane == 0) return std::nullopt;
        if (r.leaf_allowed &&
            isect_cost_ * float(refs.size()) * node_area <= traversal_cost_ * node_area + isect_cost_ * best_sum)
            return std::nullopt;
        const size_t mid = with_axis(axis, [&](auto a) {
            return size_t(std::partition(refs.begin(), refs.end(),
                                         [&](const BvhPrimRef& ref) { return bin_of(ref, a) < best_plane; }) -
                          refs.begin());
        });
        return BvhSplit{mid, axis};
    }

private:
    uint32_t bins_;
    float traversal_cost_, isect_cost_;
    std::vector<BvhBoxAccumulator> bin_bounds_;  // allocated once per build, reused by every node
    std::vector<uint32_t> bin_counts_;
    std::vector<float> right_area_;
    std::vector<uint32_t> right_count_;
    std::vector<uint64_t> used_;  // bit b: bin b is not empty
};

}  // namespace

Bvh::Bvh(const ParamSet& params) : Bvh(Config::from(params)) {}

Bvh::Bvh(const Config& config) : config_(config) {}

void Bvh::build(const Scene& scene) {
    const BvhTopDownSettings settings{config_.leaf_limit(), config_.max_depth, config_.axis};
    auto build_with = [&](auto&& strategy) { bvh_ = build_bvh_top_down(scene, settings, strategy, counts_); };
    switch (config_.split) {
        case Split::median: build_with(MedianSplit{}); break;
        case Split::midpoint: build_with(MidpointSplit{}); break;
        case Split::mean: build_with(MeanSplit{}); break;
        case Split::spatial_median: build_with(SpatialMedianSplit(scene)); break;
        case Split::sah: build_with(SahSplit(config_.bins, config_.traversal_cost, config_.isect_cost)); break;
    }
    reinsertion_counts_ = optimize_bvh_by_reinsertion(bvh_, scene, {config_.reinsertion});
    if (config_.packet_leaves()) packets_.build(bvh_);
    else packets_ = {};
}

BuildStats Bvh::build_stats() const {
    BuildStats s = bvh_build_stats(bvh_);
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
