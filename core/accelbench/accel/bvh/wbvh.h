// Wide BVH with SIMD traversal (Embree's BVH4/BVH8: Wald et al. 2014, "Embree: a kernel
// framework for efficient CPU ray tracing"; Ylitie, Karras, Laine 2017, "Efficient
// incoherent ray traversal on GPUs through compressed wide BVHs", section 3): nodes of 4 or
// 8 children whose boxes one vector slab test covers, leaves of several triangles one
// vector watertight test covers (layouts and tests: wbvh_simd.h).
//
// Build: the binned-SAH binary BVH (bvh.h with split=sah, the top-down builder of
// bvh_top_down.h, leaves of up to max_prims triangles) collapsed into a W-wide tree from the
// root down. collapse=sah (the default): the collapse of least SAH cost in wide terms, by
// dynamic programming over the binary tree (Ylitie et al. 2017, section 3.1; wbvh.cpp,
// SahCollapse), where a wide node costs one slab test of all its children and a leaf
// packet_cost per 4-triangle packet — which also decides the leaves: a binary subtree of up
// to max_prims triangles becomes one leaf when its packets cost less than a wide node over
// it, so the binary build runs finer than greedy's and the collapse merges its leaves.
// collapse=greedy, as Embree's BVH4/8 builders do: a wide node starts with its binary
// node's two children and, while it has fewer than W, replaces the child of largest surface
// area that is not a leaf by that child's two children (the largest box is the one a ray is
// most likely to enter); each binary leaf becomes one leaf child. Either way a leaf's
// triangles are ceil(n / 4) packets.
// With reinsertion=N the binary tree is first optimised by N passes of the reinsertion
// optimizer (bvh_reinsertion.h, Meister & Bittner 2018): a binary tree of lower SAH cost,
// whose collapse has fewer wide nodes on a ray's path (the conference's primary rays: 40%
// fewer node visits and box tests with N = 3), for a longer build. Off by default: it costs
// the build goal (<= 1.2x Embree) on every model.
//
// Traversal (closest hit): an explicit stack of (child, entry distance); at a node all
// children are tested at once, the children hit are sorted by entry distance, the nearest
// is entered and the others pushed far to near; a popped entry beyond the closest hit is
// skipped, and every box test is clipped to the closest hit. A leaf's packets are tested in
// turn, each against the interval shrunk by the packets before it. Any hit: the same
// without sorting (the children hit are pushed in slot order, as Embree's any-hit
// traverser does), returning at the first triangle hit.
//
// Guarantees, as the binary BVH's: the box test is intersect_box's (far distance widened by
// 2 gamma(3), Ize 2013), the triangle test intersect_triangle's (watertight, double
// precision where float cannot decide), lane for lane — the vector and scalar kernels give
// identical answers (`kernel=scalar` runs the scalar ones, compiled in every build).
//
// Counters: node_visits = wide nodes entered, box_tests = child boxes tested (a node's
// used slots, not W), prim_tests = triangles tested (a packet's used lanes). Invalid rays
// (is_valid_ray) are answered "miss" before any count.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "accelbench/accel/accelerator.h"
#include "accelbench/accel/bvh/bvh.h"
#include "accelbench/accel/bvh/wbvh_ablations.h"
#include "accelbench/accel/bvh/wbvh_simd.h"
#include "accelbench/base/huge_pages.h"

namespace accelbench {

// The tree's arrays are HugePageArrays (base/huge_pages.h): the dragon's 60 MB of wbvh8 in
// 4 KiB pages is far beyond the TLB's reach (measured there).

// A finished wide tree: nodes[0] is the root (always an inner node, even over a scene of
// one leaf), children of a node are stored after it.
template <int W>
struct WbvhTree {
    HugePageArray<WbvhNode<W>> nodes;
    HugePageArray<WbvhTriPacket> packets;
    // leaf_test=moeller only: packets[i] as Embree's Triangle4 (the ablation's leaves).
    HugePageArray<WbvhMoellerPacket> moeller_packets;
    uint32_t depth = 0;   // wide levels below the root on the longest path to a leaf child
    uint64_t leaves = 0;  // leaf children
    bool empty() const { return nodes.empty(); }
};

// Statistics of a finished wide tree (tree_tally.h): nodes = wide nodes, leaves = leaf
// children, max_depth = edges down to the deepest leaf child, sah_cost over the wide nodes'
// boxes; extras packets, packet_fill (used lanes / lanes of all packets), avg_children
// (used child slots per node) and packet_sah_cost (leaves weighted by packets, not triangles).
template <int W>
BuildStats measure_wbvh(const WbvhTree<W>& tree);

class Wbvh final : public AcceleratorBase<Wbvh> {
public:
    enum class Kernel { simd, scalar };
    enum class Collapse { greedy, sah };
    // The ablations (wbvh_ablations.h): the tests without the guarantees, to measure their price.
    enum class LeafTest { watertight, moeller };
    enum class NodeTest { conservative, fma };
    // The names, in the enums' order: the declared choices and the parser both read them.
    static constexpr std::array<std::string_view, 2> kKernelNames = {"simd", "scalar"};
    static constexpr std::array<std::string_view, 2> kCollapseNames = {"greedy", "sah"};
    static constexpr std::array<std::string_view, 2> kLeafTestNames = {"watertight", "moeller"};
    static constexpr std::array<std::string_view, 2> kNodeTestNames = {"conservative", "fma"};

    // The parameters: each member's initializer is its default; wbvh.cpp's table declares
    // them. What the defaults were measured against: docs/decisions.md, "Wide BVH".
    struct Config {
        uint32_t width = 8;  // children per node: 4 or 8
        // Leaf cap of the binary build. With collapse=sah the binary leaves are small and
        // the collapse merges a subtree into one leaf only where its packets are cheaper
        // than a node, so the cap only bounds what it may merge: 8, two packets.
        uint32_t max_prims = 8;
        uint32_t max_depth = 64;  // binary build's depth limit
        uint32_t bins = 32;       // binned SAH bins: Embree's, and `bvh split=sah`'s
        // Ranges that bin all three axes (bvh.h): none, unlike bvh's 1024, for the build goal.
        uint32_t all_axes_min = 0;
        // SAH constants of the binary build. 3: fewer, fuller leaves than 2 (26-31% fewer on
        // the bench models, nearer Embree's tree) and a faster build, for a 3-5% higher SAH
        // cost; the dragon's ray sets 2-8% faster, the others level within the spread
        // (docs/decisions.md). The collapse still merges binary leaves by its cost model.
        double traversal_cost = 3;
        double isect_cost = 1;
        // Reinsertion passes on the binary tree before the collapse; off for the build goal
        // (<= 1.2x Embree).
        uint32_t reinsertion = 0;
        Collapse collapse = Collapse::sah;  // how binary nodes are grouped into wide nodes and leaves
        double packet_cost = 2;             // collapse=sah: cost of one packet test, a wide node's = 1
        Kernel kernel = Kernel::simd;       // vector tests, or the scalar ones they must equal
        // Ablations only: the defaults are the guarantees (docs/benchmarks.md, "Ablations").
        LeafTest leaf_test = LeafTest::watertight;
        NodeTest node_test = NodeTest::conservative;
        int threads = 1;  // build threads (the same tree for every count)

        static Config from(const ParamSet& params);
    };

    static AcceleratorInfo info();
    explicit Wbvh(const ParamSet& params);

    void build(const Scene& scene) override;
    BuildStats build_stats() const override;

    template <class C>
    void intersect(const Ray& ray, Hit& hit, C& counters) const;
    template <class C>
    bool occluded(const Ray& ray, C& counters) const;

    const Config& config() const { return config_; }
    const WbvhTree<4>& tree4() const { return tree4_; }
    const WbvhTree<8>& tree8() const { return tree8_; }

private:
    template <int W>
    void collapse(const FlatBvh& binary, WbvhTree<W>& out);

    Config config_;
    Bvh binary_;  // the binned-SAH binary BVH collapsed (its buffers reused from build to build)
    BuildThreads threads_;
    WbvhTree<4> tree4_;
    WbvhTree<8> tree8_;
};

}  // namespace accelbench
