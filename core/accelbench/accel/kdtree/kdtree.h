// The SAH kd-tree of the report (section 4), after pbrt-v3's KdTreeAccel: spatial
// subdivision by axis-aligned planes chosen with the surface area heuristic, one
// primitive referenced by every leaf its bounding box overlaps, nodes in one compact
// array, front-to-back traversal with t-range culling.
//
// Two builders produce the SAME tree (same planes, same leaves, same arrays):
//   build=pbrt   sorts the bounding-box edges of every node on the axis it tries, as
//                pbrt does: O(N log^2 N).
//   build=nlogn  sorts the edges once and keeps the per-axis event lists sorted through
//                the recursion by splitting them in linear time (Wald & Havran 2006, "On
//                building fast kd-trees for ray tracing, and on doing that in O(N log N)").
// They differ only in where a node's sorted events come from; the SAH sweep, the
// classification and the leaf contents are one code path (kdtree_build.cpp). The
// traversal is kdtree_traversal.cpp, the statistics kdtree_metrics.h.
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "accelbench/accel/accelerator.h"
#include "accelbench/base/parallel.h"

namespace accelbench {

struct WatertightRay;

// One node in 8 bytes (pbrt's KdAccelNode, report Figure 12). The first child of an
// interior node is the next node of the array, so only the second ("above") child's
// index is stored. The low 2 bits of `bits_` are the split axis (0, 1, 2) or 3 for a
// leaf; the high 30 bits are the above child's index (interior) or the primitive count
// (leaf). `payload_` is the split position (interior, float bits), the primitive itself
// (leaf with one primitive: no indirection, as pbrt) or the offset of the leaf's run in
// the shared primitive-index array.
class KdNode {
public:
    static constexpr uint32_t kMaxIndex = (1u << 30) - 1;  // largest child index or count

    static KdNode interior(int axis, float split, uint32_t above_child) {
        return KdNode(std::bit_cast<uint32_t>(split), uint32_t(axis) | (above_child << 2));
    }
    static KdNode leaf(uint32_t count, uint32_t prim_or_offset) { return KdNode(prim_or_offset, 3u | (count << 2)); }
    KdNode() = default;

    bool is_leaf() const { return (bits_ & 3u) == 3u; }
    int axis() const { return int(bits_ & 3u); }
    float split() const { return std::bit_cast<float>(payload_); }
    uint32_t above_child() const { return bits_ >> 2; }
    uint32_t prim_count() const { return bits_ >> 2; }
    uint32_t single_prim() const { return payload_; }  // leaf with prim_count() == 1
    uint32_t prim_offset() const { return payload_; }  // leaf with prim_count() > 1
    // The one-element run of a leaf with prim_count() == 1: its primitive, read in place, so
    // that one loop serves both kinds of leaf.
    const uint32_t* single_prim_run() const { return &payload_; }

    bool operator==(const KdNode&) const = default;

private:
    KdNode(uint32_t payload, uint32_t bits) : payload_(payload), bits_(bits) {}
    uint32_t payload_ = 0;
    uint32_t bits_ = 3u;  // an empty leaf
};
static_assert(sizeof(KdNode) == 8, "the kd-tree node must stay 8 bytes (report 4.1.1)");

class KdTree final : public AcceleratorBase<KdTree> {
public:
    enum class BuildAlgorithm { NLogN, Pbrt };
    // The build names, in the enum's order: the declared choices and the parser both read
    // this list.
    static constexpr std::array<std::string_view, 2> kBuildNames = {"nlogn", "pbrt"};

    // The largest max_depth accepted. It sizes the traversal's fixed stack (one entry
    // per level at most), so no ray can overflow it.
    static constexpr int kMaxDepthLimit = 128;
    // Memory bound of a build: the primitive references held by the finished leaves and
    // the lists still waiting to be split may not exceed this many per triangle (with a
    // floor for small scenes). pbrt's termination rules keep real trees far below it (the
    // bunny's default tree holds 6.8 references per triangle, the dragon's 2.7, a soup of
    // heavily overlapping triangles about 80); a pathological scene with stiff parameters
    // (e.g. thousands of long crossing slivers, max_depth 128, traversal_cost 1e-4) can
    // exceed it, and the build then stops with an error naming this limit rather than
    // exhausting memory.
    static constexpr uint64_t kMaxRefsPerPrim = 256;
    static constexpr uint64_t kMinRefBudget = 1u << 22;

    // The parameters: each member's initializer is its default; kdtree.cpp's table declares them.
    struct Config {
        float isect_cost = 80.0f;     // C_I, pbrt-v3's default
        float traversal_cost = 1.0f;  // C_T
        float empty_bonus = 0.5f;     // b_e
        int max_prims = 1;
        std::optional<int> max_depth;  // empty: default_max_depth(N)
        BuildAlgorithm build = BuildAlgorithm::NLogN;
        // Reference budget override (C++ callers, tests); empty: the limit above.
        std::optional<uint64_t> max_refs;
        // Per-ray mailbox (Amanatides & Woo 1987; pbrt-v1's mailboxing): a triangle
        // referenced by several leaves along a ray is tested once. Exact: a retest over
        // the same or a shorter interval cannot answer differently.
        bool mailbox = false;
        int threads = 1;  // build threads (the same tree for every count)

        static Config from(const ParamSet& params);
    };

    static AcceleratorInfo info();
    explicit KdTree(const ParamSet& params);
    explicit KdTree(const Config& config);

    void build(const Scene& scene) override;
    // measure_kdtree() of the built tree plus what the build counted.
    BuildStats build_stats() const override;

    template <class C>
    void intersect(const Ray& ray, Hit& hit, C& counters) const;
    template <class C>
    bool occluded(const Ray& ray, C& counters) const;

    // pbrt's rule (report equation 5): round(8 + 1.3 log2 N); 8 for N <= 1.
    static int default_max_depth(size_t prim_count);

    // The built arrays, for tests that compare two trees bit for bit.
    std::span<const KdNode> nodes() const { return nodes_; }
    std::span<const uint32_t> prim_indices() const { return prim_indices_; }
    const Bounds3& bounds() const { return bounds_; }
    int max_depth_used() const { return max_depth_used_; }
    const Config& config() const { return config_; }
    uint64_t bad_refines() const { return bad_refines_; }
    int deepest_leaf() const { return deepest_leaf_; }
    uint64_t memory_bytes() const;

private:
    void build_on_threads(const Scene& scene);
    // The leaf's primitive references: `count` of them from the returned pointer.
    const uint32_t* leaf_prims(const KdNode& leaf, uint32_t& count) const;
    template <bool kMailbox, class C>
    void intersect_with(const Ray& ray, Hit& hit, C& counters) const;
    template <bool kMailbox, class C>
    bool occluded_with(const Ray& ray, C& counters) const;
    bool hit_triangle(const WatertightRay& wr, uint32_t prim, float tmin, float tmax, Hit& hit) const;

    Config config_;
    BuildThreads threads_;
    // The triangles' corners, copied in primitive order: a leaf's test then loads one
    // 36-byte record instead of an index triple and three scattered vertices (~5%
    // faster on the bunny).
    std::vector<std::array<Vec3, 3>> corners_;
    Bounds3 bounds_;
    std::vector<KdNode> nodes_;
    std::vector<uint32_t> prim_indices_;
    int max_depth_used_ = 0;
    // What only the build knows (the tree's own figures come from measure_kdtree).
    uint64_t bad_refines_ = 0;  // splits made although dearer than a leaf
    int deepest_leaf_ = 0;
};

}  // namespace accelbench
