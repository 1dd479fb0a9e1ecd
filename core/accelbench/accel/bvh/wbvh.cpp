#include "accelbench/accel/bvh/wbvh.h"

#include <tbb/task_group.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <map>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

#include "accelbench/accel/bvh/bvh_packet_leaves.h"
#include "accelbench/accel/tree_tally.h"
#include "accelbench/base/param_table.h"
#include "accelbench/base/tree_pieces.h"

namespace accelbench {

namespace {

// The parameters, each once: its row and its Config member, whose initializer is the default.
const ParamTable<Wbvh::Config>& wbvh_params() {
    using C = Wbvh::Config;
    static const ParamTable<C> rows = {
        choice_param("width", &C::width, std::array<std::string_view, 2>{"4", "8"}, std::array{4u, 8u},
                     "children per node: 4 (one SSE slab test) or 8 (one AVX slab test)"),
        int_param("max_prims", &C::max_prims, 1, BvhNode::kMaxLeafPrims,
                  "largest leaf of the binary build (SAH may stop below it); a leaf is ceil(n/4) packets"),
        int_param("max_depth", &C::max_depth, 0, 1000,
                  "binary build: nodes at this depth become leaves whatever their size"),
        int_param("bins", &C::bins, 2, 1024, "binned SAH bins along the split axis"),
        int_param("all_axes_min", &C::all_axes_min, 0, BvhNode::kMaxLeafPrims,
                  "binary build: a range of at least this many triangles takes the cheapest SAH plane over all "
                  "three axes, a smaller one the longest axis's; 1 = every range, 0 = none"),
        float_param("traversal_cost", &C::traversal_cost, 0, 1e6,
                    "SAH cost of visiting a binary node, relative to isect_cost (binary build)"),
        float_param("isect_cost", &C::isect_cost, 1e-6, 1e6, "SAH cost of one triangle test"),
        int_param("reinsertion", &C::reinsertion, 0, 100,
                  "passes of the reinsertion optimizer on the binary tree before the collapse (Meister & Bittner "
                  "2018; 0 = off): lower SAH cost for a longer build, the same answers"),
        enum_param("collapse", &C::collapse, Wbvh::kCollapseNames,
                   "how the binary tree becomes wide nodes: greedy (Embree: open the largest child until W; each "
                   "binary leaf a leaf; best with max_prims=4 traversal_cost=3) or sah (Ylitie et al. 2017: the "
                   "least wide SAH cost by dynamic programming, which also merges binary subtrees into leaves of up "
                   "to max_prims)"),
        float_param("packet_cost", &C::packet_cost, 1e-6, 1e6,
                    "collapse=sah: cost of one 4-triangle packet test relative to one wide node (one slab test of "
                    "all its children)"),
        enum_param("kernel", &C::kernel, Wbvh::kKernelNames,
                   "simd: the vector slab and triangle tests compiled in (scalar on a target without SSE2); "
                   "scalar: the scalar forms, identical answers (for testing and measuring the vector gain)"),
        enum_param("leaf_test", &C::leaf_test, Wbvh::kLeafTestNames,
                   "ablation: watertight (Woop et al. 2013, the default) or moeller (Moeller-Trumbore in float on "
                   "triangles precomputed as Embree's Triangle4: not watertight, for measuring the price)"),
        enum_param("node_test", &C::node_test, Wbvh::kNodeTestNames,
                   "ablation: conservative (far distance widened, Ize 2013, the default) or fma (one fused "
                   "multiply-add per plane, unwidened, as Embree's non-robust test: not conservative)"),
        threads_param("threads", &C::threads,
                      "build threads (0 = all cores), the binary build's and the collapse's; the tree is the same "
                      "for every value"),
    };
    return rows;
}

// The binary BVH's configuration: split=sah and the build parameters wbvh shares with it
// (reinsertion included: the optimizer runs on the binary tree, which the collapse then
// reads as it reads any binary tree — same leaves, boxes refitted).
Bvh::Config binary_config(const Wbvh::Config& c) {
    Bvh::Config b;
    b.split = Bvh::Split::sah;
    b.max_prims = c.max_prims;
    b.max_depth = c.max_depth;
    b.bins = c.bins;
    b.all_axes_min = c.all_axes_min;
    b.traversal_cost = float(c.traversal_cost);
    b.isect_cost = float(c.isect_cost);
    b.reinsertion = c.reinsertion;
    // The collapse reads the binary tree's triangle copies, and the binary tree is never
    // traced: no packet leaves (which would release the copies, bvh.cpp).
    b.leaf_test = Bvh::Config::LeafTest::scalar;
    b.threads = c.threads;  // the binary build on the wide BVH's threads
    return b;
}

}  // namespace

AcceleratorInfo Wbvh::info() {
    return {.name = "wbvh",
            .description =
                "wide BVH (Embree BVH4/BVH8): the binned-SAH binary BVH collapsed to 4 or 8 children per "
                "node, child boxes structure-of-arrays in one SIMD slab test, leaves of 4-triangle packets "
                "in one SIMD watertight test",
            .params = wbvh_params().specs(),
            .create = [](const ParamSet& p) { return std::make_unique<Wbvh>(p); },
            .label =
                [](const ParamSet& p) {
                    std::string ablation;
                    if (p.get_enum("leaf_test") != "watertight") ablation += ", ablation " + p.get_enum("leaf_test");
                    if (p.get_enum("node_test") != "conservative") ablation += ", ablation " + p.get_enum("node_test");
                    return "wide BVH (" + p.get_enum("width") + ", " +
                        (p.get_enum("kernel") == "simd" ? "SIMD" : "scalar") + ablation + ")";
                },
            // The ablations give up the guarantees: leaks through edges (moeller) or past
            // box faces (fma) are counted by the catalogue, not required.
            .watertight =
                [](const ParamSet& p) {
                    const Config c = Config::from(p);
                    return c.leaf_test == LeafTest::watertight && c.node_test == NodeTest::conservative;
                },
            // Every wide child lies at least one binary level below its node, so the wide
            // tree is no deeper than the binary one, except that the wide root is an inner
            // node even over a single binary leaf (max_depth=0): a leaf child at depth 1.
            .depth_limit = [](const ParamSet& p) -> std::optional<uint64_t> {
                return std::max<uint64_t>(1, Config::from(p).max_depth);
            }};
}

Wbvh::Config Wbvh::Config::from(const ParamSet& params) { return wbvh_params().from(params); }

Wbvh::Wbvh(const ParamSet& params)
    : config_(Config::from(params)), binary_(binary_config(config_)), threads_(config_.threads) {}

namespace {

// A child slot of a wide node as a collapse chooses it: the binary node whose subtree it
// covers, and whether that subtree becomes one leaf child (its triangles in packets) or an
// inner child (a wide node of its own, chosen the same way).
struct CollapseChild {
    uint32_t binary;
    bool leaf;
};

// collapse=greedy (Embree's BVH4/8 builders): the binary node's two children, then the
// inner child of largest surface area opened until W. Leaf children are the binary leaves.
template <int W>
int greedy_children(const FlatBvh& binary, uint32_t node, CollapseChild out[W]) {
    int n = 0;
    const BvhNode& b = binary.nodes[node];
    if (b.is_leaf()) {
        out[n++] = {node, true};  // the whole tree is one leaf: a root with one leaf child
        return n;
    }
    out[n++] = {node + 1, false};
    out[n++] = {b.second_child(), false};
    while (n < W) {
        int open = -1;
        float open_area = -1.0f;
        for (int k = 0; k < n; ++k) {
            const BvhNode& c = binary.nodes[out[k].binary];
            if (c.is_leaf()) continue;
            const float area = c.bounds.area();
            if (area > open_area) {
                open = k;
                open_area = area;
            }
        }
        if (open < 0) break;
        const uint32_t opened = out[open].binary;
        out[open].binary = opened + 1;
        out[n++] = {binary.nodes[opened].second_child(), false};
    }
    for (int k = 0; k < n; ++k) out[k].leaf = binary.nodes[out[k].binary].is_leaf();
    return n;
}

// collapse=sah: the collapse of least SAH cost in wide terms, by dynamic programming over
// the binary tree (Ylitie, Karras, Laine 2017, section 3.1). For a binary node n and
// i = 1..W, cost(n, i) is the least cost of covering n's subtree by at most i child slots
// of the wide node above it:
//   cost(n, 1)  = min(leaf(n), A(n) * 1 + distribute(n, W))  a leaf child, or a wide node
//   cost(n, i)  = min(cost(n, i - 1), distribute(n, i))
//   distribute(n, j) = min over 1 <= k < j of cost(left, k) + cost(right, j - k)
//   leaf(n)     = A(n) * packet_cost * ceil(triangles / 4)   (max_prims triangles at most)
// with A the surface area (the probability of a ray entering the box, up to the root's
// area, which is the same for all collapses), a wide node costing 1 — one slab test of all
// its children — and a leaf its packet tests. A binary leaf is always a leaf; an inner node
// becomes one when its triangles in packets cost less than a wide node over them, so the
// collapse also merges small binary leaves into fuller packets. O(N * W^2) for N binary nodes.
template <int W>
class SahCollapse {
public:
    // The plan of every binary node: children are stored after their parent (depth-first),
    // so one pass from the back; on the build's threads the two subtrees of a large node at
    // once (each node's plan depends on its children's alone).
    SahCollapse(const FlatBvh& binary, uint32_t max_prims, double packet_cost, bool parallel)
        : binary_(binary),
          plan_(binary.nodes.size()),
          prims_(binary.nodes.size()),
          max_prims_(max_prims),
          packet_cost_(float(packet_cost)) {
        plan_subtree(0, parallel);
        // The root is a wide node whatever its cost: one leaf child under it when that is
        // cheaper than distributing the tree over its W slots.
        root_is_leaf_ = binary.nodes[0].is_leaf() ||
            (prims_[0] <= max_prims &&
             leaf_cost(binary.nodes[0].bounds.area(), prims_[0], packet_cost_) <= root_distribute_);
    }

    // The children of the wide node over binary node `node` (the root or an inner child).
    int children(uint32_t node, CollapseChild out[W]) const {
        int n = 0;
        if (node == 0 && root_is_leaf_) {
            out[n++] = {0, true};
            return n;
        }
        const uint32_t k = plan_[node].node_split;
        gather(node + 1, k, out, n);
        gather(binary_.nodes[node].second_child(), W - k, out, n);
        return n;
    }

private:
    static float leaf_cost(float area, uint32_t n, float packet_cost) {
        return area * packet_cost * float(WbvhTriPacket::packets_for(n));
    }

    void plan_subtree(uint32_t m, bool parallel) {
        constexpr size_t kSerial = 1 << 14;  // binary nodes
        const size_t end = subtree_end(binary_, m);
        if (!parallel || end - m < kSerial) {
            for (size_t i = end; i-- > m;) plan_node(uint32_t(i));
            return;
        }
        fork_join(
            true, [&] { plan_subtree(m + 1, true); }, [&] { plan_subtree(binary_.nodes[m].second_child(), true); });
        plan_node(m);
    }

    // Every member it reads is copied to a local first: the byte stores into the plans may
    // alias anything, as far as the compiler knows, and would make it reload the members.
    void plan_node(uint32_t m) {
        const BvhNode& b = binary_.nodes[m];
        Plan* const plans = plan_.data();
        uint32_t* const prims = prims_.data();
        const uint32_t max_prims = max_prims_;
        const float packet_cost = packet_cost_;
        Plan& p = plans[m];
        const float area = b.bounds.area();
        if (b.is_leaf()) {
            const float cost = leaf_cost(area, b.prim_count(), packet_cost);
            prims[m] = b.prim_count();
            for (int i = 0; i < W; ++i) p.cost[i] = cost;
            p.leaf = true;
            return;
        }
        const uint32_t l = m + 1, r = b.second_child();
        const uint32_t n = prims[l] + prims[r];
        prims[m] = n;
        const Plan &pl = plans[l], &pr = plans[r];
        float dist[W + 1];
        uint8_t split[W + 1];
        for (int j = 2; j <= W; ++j) {
            dist[j] = kInfinity;
            split[j] = 1;
            for (int k = 1; k < j; ++k) {  // branch-free (minss and cmov): the outcome is data, not a pattern
                const float c = pl.cost[k - 1] + pr.cost[j - k - 1];
                const bool lower = c < dist[j];
                dist[j] = lower ? c : dist[j];
                split[j] = lower ? uint8_t(k) : split[j];
            }
        }
        p.node_split = split[W];
        if (m == 0) root_distribute_ = dist[W];
        const float node = area + dist[W];
        const float leaf = n <= max_prims ? leaf_cost(area, n, packet_cost) : kInfinity;
        p.leaf = n <= max_prims && leaf <= node;  // a tie: the leaf, one node fewer
        p.cost[0] = p.leaf ? leaf : node;
        p.split[0] = 0;
        for (int i = 2; i <= W; ++i) {
            const bool fewer = !(dist[i] < p.cost[i - 2]);  // fewer slots are as cheap (or NaN)
            p.cost[i - 1] = fewer ? p.cost[i - 2] : dist[i];
            p.split[i - 1] = fewer ? 0 : split[i];
        }
    }

    struct Plan {
        float cost[W];           // cost(n, i + 1)
        uint8_t split[W] = {};   // i > 0: k of distribute(n, i + 1), 0 when cost(n, i) is as low
        uint8_t node_split = 1;  // k of distribute(n, W): the wide node over n
        bool leaf = false;       // cost(n, 1) is a leaf child
    };

    // The children of at most `slots` slots covering binary node m's subtree.
    void gather(uint32_t m, uint32_t slots, CollapseChild out[W], int& n) const {
        const Plan& p = plan_[m];
        while (slots > 1 && p.split[slots - 1] == 0) --slots;
        if (slots == 1) {
            out[n++] = {m, p.leaf};
            return;
        }
        const uint32_t k = p.split[slots - 1];
        gather(m + 1, k, out, n);
        gather(binary_.nodes[m].second_child(), slots - k, out, n);
    }

    const FlatBvh& binary_;
    std::vector<Plan> plan_;
    std::vector<uint32_t> prims_;  // triangles under each binary node
    uint32_t max_prims_;
    float packet_cost_;
    float root_distribute_ = kInfinity;  // distribute(root, W)
    bool root_is_leaf_ = false;
};

// A leaf child over binary node m: the triangles of its subtree's leaves, left to right, in
// ceil(n / 4) packets. Returns the number of triangles.
uint32_t emit_leaf(const FlatBvh& binary, uint32_t m, HugePageArray<WbvhTriPacket>& packets,
                   std::vector<uint32_t>& slots, std::vector<uint32_t>& stack) {
    slots.clear();
    stack.assign(1, m);
    while (!stack.empty()) {
        const uint32_t i = stack.back();
        stack.pop_back();
        const BvhNode& b = binary.nodes[i];
        if (b.is_leaf()) {
            for (uint32_t s = 0; s < b.prim_count(); ++s) slots.push_back(b.first_prim() + s);
        } else {
            stack.push_back(b.second_child());
            stack.push_back(i + 1);
        }
    }
    const uint32_t count = uint32_t(slots.size());
    for (uint32_t first = 0; first < count; first += WbvhTriPacket::kLanes)
        packets.push_back(pack_triangles(
            binary, std::span(slots).subspan(first, std::min<uint32_t>(WbvhTriPacket::kLanes, count - first))));
    return count;
}

}  // namespace

namespace {

template <int W>
using WbvhPiece = TreePiece<WbvhNode<W>, WbvhTriPacket, HugePageArray<WbvhNode<W>>, HugePageArray<WbvhTriPacket>>;

// Writes the wide tree the collapse chooses. A wide node's inner children get consecutive
// slots when it is written, then their subtrees follow, the last child's first (the order of
// the explicit stack this once was). On the build's threads, an inner child's subtree near
// the top is handed out as a task (base/parallel.h), written into a piece of its own
// (base/tree_pieces.h) that goes where its subtree would have started; the assembled arrays
// are the one thread's.
template <int W>
class WideEmitter {
public:
    // What one task writes.
    struct Output {
        explicit Output(WbvhPiece<W>& p) : piece(p) {}
        WbvhPiece<W>& piece;
        uint32_t depth = 0;                  // deepest wide node (root: 0)
        uint64_t leaves = 0;                 // leaf children
        std::vector<uint32_t> slots, stack;  // emit_leaf's scratch
    };

    WideEmitter(const FlatBvh& binary, const SahCollapse<W>* sah, bool parallel)
        : binary_(binary), sah_(sah), parallel_(parallel) {}

    // The wide node over binary node `b` at wide depth `depth`, its leaves' packets and its
    // inner children's subtrees written to out.piece; its references are local to that piece.
    WbvhNode<W> node_over(uint32_t b, uint32_t depth, Output& out) const {
        out.depth = std::max(out.depth, depth);
        CollapseChild kids[W];
        const int n = sah_ ? sah_->children(b, kids) : greedy_children<W>(binary_, b, kids);
        // Slots by decreasing surface area. The closest-hit traversal orders hit children by
        // distance, whatever their slots; the any-hit one enters the first hit slot, so there
        // the likeliest box to hold an occluder goes first. Measured (sah collapse, counts
        // over the 640x480 primary + shadow rays, width 8): prim tests per ray bunny 1.91 ->
        // 1.84, conference 5.20 -> 5.07, igea 2.06 -> 1.96, dragon 2.02 -> 1.93, node visits
        // 0.3-1% fewer. Leaves first, or inner children first, then by area: no better.
        // (Insertion sort, stable: std::stable_sort's buffer cost 35M instructions on igea.)
        float area[W];
        for (int k = 0; k < n; ++k) {
            const CollapseChild c = kids[k];
            const float a = binary_.nodes[c.binary].bounds.area();
            int i = k;
            for (; i > 0 && area[i - 1] < a; --i) {
                kids[i] = kids[i - 1];
                area[i] = area[i - 1];
            }
            kids[i] = c;
            area[i] = a;
        }
        WbvhNode<W> node;
        for (int a = 0; a < 3; ++a)
            for (int k = 0; k < W; ++k) {
                node.planes[a][k] = kInfinity;
                node.planes[3 + a][k] = -kInfinity;
            }
        for (int k = 0; k < W; ++k) {
            node.child[k] = kInvalidId;
            node.count[k] = 0;
        }
        int inner[W], inner_count = 0;
        for (int k = 0; k < n; ++k) {
            const BvhNode& c = binary_.nodes[kids[k].binary];
            for (int a = 0; a < 3; ++a) {
                node.planes[a][k] = c.bounds.lower[a];
                node.planes[3 + a][k] = c.bounds.upper[a];
            }
            if (kids[k].leaf) {
                ++out.leaves;
                node.child[k] = uint32_t(out.piece.items.size());
                node.count[k] = emit_leaf(binary_, kids[k].binary, out.piece.items, out.slots, out.stack);
            } else {
                node.child[k] = uint32_t(out.piece.nodes.size());
                out.piece.nodes.emplace_back();  // written below (HugePageAllocator leaves it unwritten)
                inner[inner_count++] = k;
            }
        }
        struct Task {
            WbvhPiece<W>* piece;
            uint32_t slot, binary;
            Output out;
            WbvhNode<W> node;
        };
        std::vector<std::unique_ptr<Task>> tasks;
        for (int j = inner_count; j-- > 0;) {
            const int k = inner[j];
            if (hand_out(kids[k].binary, depth + 1)) {
                auto piece = std::make_unique<WbvhPiece<W>>();
                auto task =
                    std::make_unique<Task>(Task{piece.get(), node.child[k], kids[k].binary, Output(*piece), {}});
                out.piece.add_hole(node.child[k], std::move(piece));
                tasks.push_back(std::move(task));
                continue;
            }
            const WbvhNode<W> child = node_over(kids[k].binary, depth + 1, out);
            out.piece.nodes[node.child[k]] = child;
        }
        if (!tasks.empty()) {
            tbb::task_group group;
            for (const auto& t : tasks)
                group.run(
                    [this, task = t.get(), depth] { task->node = node_over(task->binary, depth + 1, task->out); });
            group.wait();
            for (const auto& t : tasks) {
                out.piece.nodes[t->slot] = t->node;
                out.depth = std::max(out.depth, t->out.depth);
                out.leaves += t->out.leaves;
            }
        }
        return node;
    }

private:
    // A subtree handed out: near the top, and large enough to pay for a task and a piece.
    bool hand_out(uint32_t b, uint32_t depth) const {
        constexpr uint32_t kTaskDepth = 3;         // wide levels whose subtrees may be tasks
        constexpr size_t kTaskBinaryNodes = 2048;  // binary nodes a task covers at least
        return parallel_ && depth <= kTaskDepth && subtree_end(binary_, b) - b >= kTaskBinaryNodes;
    }

    const FlatBvh& binary_;
    const SahCollapse<W>* sah_;
    bool parallel_;
};

}  // namespace

// The collapse (see wbvh.h).
template <int W>
void Wbvh::collapse(const FlatBvh& binary, WbvhTree<W>& out) {
    out.nodes.clear();
    out.packets.clear();
    out.depth = 0;
    out.leaves = 0;
    if (binary.empty()) return;
    const bool parallel = threads_.parallel();
    std::optional<SahCollapse<W>> sah;
    if (config_.collapse == Collapse::sah) sah.emplace(binary, config_.max_prims, config_.packet_cost, parallel);

    WbvhPiece<W> root;
    root.nodes.swap(out.nodes);
    root.items.swap(out.packets);
    if (!parallel) {
        root.nodes.reserve(binary.nodes.size() / 2 + 1);  // each wide node replaces at least one binary inner node
        root.items.reserve(binary.prim_ids.size() / 2 + 1);
    }
    typename WideEmitter<W>::Output emitted(root);
    root.nodes.emplace_back();
    const WbvhNode<W> top = WideEmitter<W>(binary, sah ? &*sah : nullptr, parallel).node_over(0, 0, emitted);
    root.nodes[0] = top;
    out.depth = emitted.depth;
    out.leaves = emitted.leaves;
    if (root.holes.empty()) {
        out.nodes.swap(root.nodes);
        out.packets.swap(root.items);
        return;
    }
    const auto [nodes, packets] = root.layout();
    out.nodes.resize(nodes);  // not written (HugePageAllocator)
    out.packets.resize(packets);
    root.assemble(out.nodes.data(), out.packets.data(), parallel,
                  [](WbvhNode<W>& node, const typename WbvhPiece<W>::Map&, const typename WbvhPiece<W>::Map& refs) {
                      for (int k = 0; k < W; ++k) {
                          if (node.child[k] == kInvalidId) continue;
                          node.child[k] = uint32_t(node.count[k] ? refs.item(node.child[k]) : refs.node(node.child[k]));
                      }
                  });
}

namespace {

template <int W>
void moeller_leaves(WbvhTree<W>& tree) {
    tree.moeller_packets.resize(tree.packets.size());
    for (size_t i = 0; i < tree.packets.size(); ++i) tree.moeller_packets[i] = WbvhMoellerPacket::from(tree.packets[i]);
}

}  // namespace

void Wbvh::build(const Scene& scene) {
    binary_.build(scene);
    threads_.run([&] {
        if (config_.width == 8) {
            collapse(binary_.tree(), tree8_);
            tree4_ = {};
        } else {
            collapse(binary_.tree(), tree4_);
            tree8_ = {};
        }
        if (config_.leaf_test == LeafTest::moeller) {
            moeller_leaves(tree8_);
            moeller_leaves(tree4_);
        }
    });
}

template <int W>
BuildStats measure_wbvh(const WbvhTree<W>& tree) {
    TreeTally t;
    t.nodes = tree.nodes.size();
    t.max_depth = tree.empty() ? 0 : tree.depth + 1;  // edges down to the deepest leaf child
    t.memory_bytes = tree.nodes.size() * sizeof(WbvhNode<W>) + tree.packets.size() * sizeof(WbvhTriPacket) +
        tree.moeller_packets.size() * sizeof(WbvhMoellerPacket);
    uint64_t children = 0;
    double packet_area = 0;  // leaves' areas weighted by their packets
    for (size_t i = 0; i < tree.nodes.size(); ++i) {
        const WbvhNode<W>& node = tree.nodes[i];
        Bounds3 box;
        const uint32_t n = node.child_count();
        children += n;
        for (uint32_t k = 0; k < n; ++k) {
            const Bounds3 b = node.child_bounds(int(k));
            box.extend(b);
            if (node.count[k]) {
                t.leaf(b.area(), node.count[k]);
                packet_area += b.area() * double(WbvhTriPacket::packets_for(node.count[k]));
            }
        }
        t.inner(box.area());
        if (i == 0) t.root_area = box.area();
    }
    BuildStats s = t.stats();
    const uint64_t packets = tree.packets.size();
    s.extra["packets"] = double(packets);
    s.extra["packet_fill"] = packets ? double(t.prim_refs) / double(packets * WbvhTriPacket::kLanes) : 0.0;
    s.extra["avg_children"] = t.nodes ? double(children) / double(t.nodes) : 0.0;
    // The SAH cost in the form of Embree's printed statistics (verbose=2; its
    // bvh_statistics.cpp): a wide node 1, a leaf 1 per 4-triangle block, for comparing trees.
    if (t.root_area > 0) s.extra["packet_sah_cost"] = (t.inner_area + packet_area) / t.root_area;
    return s;
}

template BuildStats measure_wbvh(const WbvhTree<4>&);
template BuildStats measure_wbvh(const WbvhTree<8>&);

BuildStats Wbvh::build_stats() const {
    BuildStats s = config_.width == 8 ? measure_wbvh(tree8_) : measure_wbvh(tree4_);
    const BuildStats binary = binary_.build_stats();
    s.extra["binary_nodes"] = double(binary.nodes.value_or(0));
    if (binary.sah_cost) s.extra["binary_sah_cost"] = *binary.sah_cost;
    for (const char* key : {"degenerate_splits", "forced_leaves", "reinsertions"}) {
        const auto it = binary.extra.find(key);
        if (it != binary.extra.end()) s.extra[key] = it->second;
    }
    return s;
}

namespace {

// A child as WbvhNode stores it: count 0, inner node `child`; else a leaf of `count`
// triangles at packet `child`. The any-hit traversal's stack entry: its tmax does not
// shrink before it returns, so the test that skips a popped entry beyond tmax (an entry
// distance in (tmax, tmax + slack], which the widened box test accepts) is made when the
// child is pushed instead, and the entry keeps no distance.
struct ChildRef {
    uint32_t child, count;
};

// The closest-hit traversal's stack entry: the child and its entry distance (a popped
// entry beyond the closest hit is skipped).
struct StackEntry {
    ChildRef ref;
    float tnear;
};

// Entries for any tree: each node pushes at most W - 1 of its children and descends into
// one, so (W - 1) * depth + 1 entries suffice. Shallow trees (all balanced ones) use the
// inline array; deeper ones allocate once per ray.
template <class Entry>
class Stack {
public:
    Stack(uint32_t width, uint32_t depth) {
        const size_t need = size_t(width - 1) * (size_t(depth) + 1) + 1;
        if (need > kInline) {
            heap_ = std::make_unique<Entry[]>(need);
            data_ = heap_.get();
        }
    }
    Entry* bottom() { return data_; }

private:
    static constexpr size_t kInline = 256;
    Entry inline_[kInline];
    std::unique_ptr<Entry[]> heap_;
    Entry* data_ = inline_;
};

// A sort key that orders children by entry distance: the distance's bits made to compare
// as unsigned integers in float order, the lowest 3 bits replaced by the child's slot (so
// equal keys cannot occur, and the slot travels with the key). The order is that of the
// distances up to 8 ulps — an order of visit only; the exact distance goes on the stack.
inline uint32_t order_key(float t, int slot) {
    const uint32_t bits = std::bit_cast<uint32_t>(t);
    const uint32_t ordered = (bits & 0x80000000u) ? ~bits : bits | 0x80000000u;
    return (ordered & ~7u) | uint32_t(slot);
}

template <int W>
inline ChildRef child_ref(const WbvhNode<W>& node, int k) {
    return {node.child[k], node.count[k]};
}

#if defined(ACCELBENCH_WBVH_AVX)
// The closest-hit order of the children hit (`mask`, three or more) without a sort: a child's
// place is its rank, the number of children hit with a smaller order_key, found by one
// compare of its key against all eight. The keys are order_key's as signed integers (a
// float's bits with the magnitude flipped for negatives, the slot in the low 3 bits), so
// they are distinct and the order is the insertion sort's: the same visits, the same
// answers. Pushes ranks n-1..1 far to near from `top` (the farthest deepest), sets `cur`
// to rank 0 and returns the new top; rank 0 is written one past the pushes first, a slot
// the stack's bound leaves free (W - 1 spare entries), so no branch depends on the rank.
inline StackEntry* push_by_rank(const WbvhNode<8>& node, uint32_t mask, const float (&tnear)[8], StackEntry* top,
                                ChildRef& cur) {
    const __m256i bits = _mm256_castps_si256(_mm256_loadu_ps(tnear));
    const __m256i ordered = _mm256_xor_si256(bits, _mm256_srli_epi32(_mm256_srai_epi32(bits, 31), 1));
    const __m256i keys =
        _mm256_or_si256(_mm256_and_si256(ordered, _mm256_set1_epi32(~7)), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    const int last = std::popcount(mask) - 1;
    for (uint32_t m = mask; m; m &= m - 1) {
        const int k = std::countr_zero(m);
        const __m256i key = _mm256_permutevar8x32_epi32(keys, _mm256_set1_epi32(k));
        const uint32_t smaller = uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(key, keys))));
        top[last - std::popcount(smaller & mask)] = {child_ref(node, k), tnear[k]};
    }
    cur = top[last].ref;
    return top + last;
}
#endif

// Closest hit (kAnyHit false): `hit` must come in empty and receives the closest hit; the
// interval shrinks to it. Any hit: the children hit are pushed in slot order, as Embree's
// any-hit traverser does, and it returns at the first triangle hit.
// The tests of a traversal: the guarantees (both false, the default) or the ablations
// (wbvh_ablations.h), each in the scalar or the vector form.
template <int W, bool kVector, bool kMoeller, bool kFma>
struct Tests {
    static constexpr bool kAblation = kMoeller || kFma;
    struct None {
        explicit None(const Ray&) {}
    };
    // The ablations' per-ray constants, made only where one runs.
    using AblationRay = std::conditional_t<kAblation, WbvhAblationRay<W>, None>;

    static uint32_t node(const WbvhNode<W>& node, const WbvhRay<W, kVector>& r, const AblationRay& a, float tmin,
                         float tmax, float (&tnear)[W]) {
        if constexpr (kFma) {
#if defined(ACCELBENCH_WBVH_SSE) && defined(__FMA__)
            if constexpr (kVector) return wbvh_slab_test_fma_vector(node, a, tmin, tmax, tnear);
#endif
            return wbvh_slab_test_fma(node, a, tmin, tmax, tnear);
        } else {
            (void)a;
            return wbvh_slab_test(node, r, tmin, tmax, tnear);
        }
    }

    // Where leaf child `first`'s packets start (the ablation's own packets for moeller).
    static const char* leaf_bytes(const WbvhTree<W>& tree, uint32_t first) {
        if constexpr (kMoeller) return reinterpret_cast<const char*>(&tree.moeller_packets[first]);
        else return reinterpret_cast<const char*>(&tree.packets[first]);
    }

    template <bool kAnyHit, class C>
    static bool leaf(const WbvhTree<W>& tree, ChildRef ref, const WbvhRay<W, kVector>& r, const AblationRay& a,
                     float tmin, float& tmax, Hit& hit, C& c) {
        if constexpr (kMoeller) {
            const auto test = [&](const WbvhMoellerPacket& p, int lanes, float t_max) {
#if defined(ACCELBENCH_WBVH_SSE)
                if constexpr (kVector) return wbvh_moeller_test(p, lanes, a.org4, a.dir4, tmin, t_max);
#endif
                return wbvh_moeller_test(p, lanes, a.org, a.dir, tmin, t_max);
            };
            return wbvh_leaf_packets<kAnyHit>(&tree.moeller_packets[ref.child], ref.count, test, tmax, hit, c);
        } else {
            (void)a;
            return wbvh_leaf_test<kAnyHit>(&tree.packets[ref.child], ref.count, r, tmin, tmax, hit, c);
        }
    }
};

template <int W, bool kVector, bool kAnyHit, class T, class C>
ACCELBENCH_BVH_HOT bool traverse(const WbvhTree<W>& tree, const Ray& ray, Hit& hit, C& c) {
    if (tree.empty()) return false;
    const WbvhRay<W, kVector> r(ray);
    if (!r.valid) return false;
    const typename T::AblationRay ablation(ray);
    const float tmin = ray.tmin;
    float tmax = ray.tmax;
    using Entry = std::conditional_t<kAnyHit, ChildRef, StackEntry>;
    Stack<Entry> storage(W, tree.depth);
    Entry* const bottom = storage.bottom();
    Entry* top = bottom;
    ChildRef cur{0, 0};  // the root
    for (;;) {
        while (cur.count == 0) {  // an inner node
            c.node();
            const WbvhNode<W>& node = tree.nodes[cur.child];
#if defined(ACCELBENCH_WBVH_SSE)
            _mm_prefetch(reinterpret_cast<const char*>(node.child), _MM_HINT_T0);  // with the planes
#endif
            c.box(node.child_count());
            float tnear[W];
            uint32_t mask = T::node(node, r, ablation, tmin, tmax, tnear);
            if (mask == 0) goto pop;
#if defined(ACCELBENCH_WBVH_SSE)
            // Every child hit: its node's lines, or its first packet's, requested now, so the
            // misses of the children visited later overlap with this node's work.
            for (uint32_t m = mask; m; m &= m - 1) {
                const int k = std::countr_zero(m);
                const char* p = node.count[k] ? T::leaf_bytes(tree, node.child[k])
                                              : reinterpret_cast<const char*>(&tree.nodes[node.child[k]]);
                _mm_prefetch(p, _MM_HINT_T0);
                _mm_prefetch(p + 64, _MM_HINT_T0);
                _mm_prefetch(p + 128, _MM_HINT_T0);
                if (sizeof(WbvhNode<W>) > 192 && !node.count[k]) _mm_prefetch(p + 192, _MM_HINT_T0);
            }
#endif
            const int first = std::countr_zero(mask);
            mask &= mask - 1;
            if constexpr (kAnyHit) {
                // Any occluder ends the search, so the order is not worth sorting for (Embree's
                // any-hit traverser, traverseAnyHit, does not sort either; measured here: sorting
                // made the bunny's shadow rays ~15% slower in all). An entry beyond tmax, which
                // the closest-hit pop skips, is not pushed: tmax does not shrink here.
                for (; mask; mask &= mask - 1) {
                    const int k = std::countr_zero(mask);
                    if (tnear[k] <= tmax) *top++ = child_ref(node, k);
                }
                cur = child_ref(node, first);
            } else {
                if (mask == 0) {  // one child hit: no ordering
                    cur = child_ref(node, first);
                    continue;
                }
                if ((mask & (mask - 1)) == 0) {  // two: one comparison of their keys
                    const int second = std::countr_zero(mask);
                    const bool swap = order_key(tnear[second], second) < order_key(tnear[first], first);
                    const int near = swap ? second : first, far = swap ? first : second;
                    *top++ = {child_ref(node, far), tnear[far]};
                    cur = child_ref(node, near);
                    continue;
                }
                // More: pushed far to near, the nearest entered.
#if defined(ACCELBENCH_WBVH_AVX)
                if constexpr (W == 8 && kVector) {
                    top = push_by_rank(node, mask | 1u << first, tnear, top, cur);
                    continue;
                }
#endif
                // Sort their keys (insertion sort, at most 8).
                uint32_t keys[W];
                int n = 0;
                keys[n++] = order_key(tnear[first], first);
                for (; mask; mask &= mask - 1) {
                    const int k = std::countr_zero(mask);
                    const uint32_t key = order_key(tnear[k], k);
                    int i = n++;
                    for (; i > 0 && keys[i - 1] > key; --i) keys[i] = keys[i - 1];
                    keys[i] = key;
                }
                for (int i = n - 1; i > 0; --i) {
                    const int k = int(keys[i] & 7u);
                    *top++ = {child_ref(node, k), tnear[k]};
                }
                cur = child_ref(node, int(keys[0] & 7u));
            }
        }
        // A leaf: its packets in turn, each against the interval shrunk by those before it.
        // (An 8-lane test of two packets and 8-byte stack entries: docs/decisions.md.)
        if (T::template leaf<kAnyHit>(tree, cur, r, ablation, tmin, tmax, hit, c) && kAnyHit) return true;
    pop:
        for (;;) {
            if (top == bottom) return hit.found();
            --top;
            if constexpr (kAnyHit) {
                cur = *top;
                break;
            } else if (top->tnear <= tmax) {
                cur = top->ref;
                break;
            }
        }
    }
}

template <bool kAnyHit, bool kMoeller, bool kFma, class C>
bool dispatch_tests(const Wbvh& w, const Ray& ray, Hit& hit, C& c) {
    const bool vector = w.config().kernel == Wbvh::Kernel::simd;
    if (w.config().width == 8)
        return vector ? traverse<8, true, kAnyHit, Tests<8, true, kMoeller, kFma>>(w.tree8(), ray, hit, c)
                      : traverse<8, false, kAnyHit, Tests<8, false, kMoeller, kFma>>(w.tree8(), ray, hit, c);
    return vector ? traverse<4, true, kAnyHit, Tests<4, true, kMoeller, kFma>>(w.tree4(), ray, hit, c)
                  : traverse<4, false, kAnyHit, Tests<4, false, kMoeller, kFma>>(w.tree4(), ray, hit, c);
}

template <bool kAnyHit, class C>
bool dispatch(const Wbvh& w, const Ray& ray, Hit& hit, C& c) {
    const bool moeller = w.config().leaf_test == Wbvh::LeafTest::moeller;
    const bool fma = w.config().node_test == Wbvh::NodeTest::fma;
    if (moeller)
        return fma ? dispatch_tests<kAnyHit, true, true>(w, ray, hit, c)
                   : dispatch_tests<kAnyHit, true, false>(w, ray, hit, c);
    return fma ? dispatch_tests<kAnyHit, false, true>(w, ray, hit, c)
               : dispatch_tests<kAnyHit, false, false>(w, ray, hit, c);
}

}  // namespace

template <class C>
void Wbvh::intersect(const Ray& ray, Hit& hit, C& counters) const {
    dispatch<false>(*this, ray, hit, counters);
}

template <class C>
bool Wbvh::occluded(const Ray& ray, C& counters) const {
    Hit unused;
    return dispatch<true>(*this, ray, unused, counters);
}

ACCELBENCH_INSTANTIATE_RAY_QUERIES(Wbvh);

}  // namespace accelbench
