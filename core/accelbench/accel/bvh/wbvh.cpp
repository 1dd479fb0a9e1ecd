#include "accelbench/accel/bvh/wbvh.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>

#include "accelbench/accel/bvh/bvh_metrics.h"

namespace accelbench {

AcceleratorInfo Wbvh::info() {
    return {"wbvh",
            "wide BVH (Embree BVH4/BVH8): the binned-SAH binary BVH collapsed to 4 or 8 children per node, child "
            "boxes structure-of-arrays in one SIMD slab test, leaves of 4-triangle packets in one SIMD watertight test",
            {
                {"width",
                 ParamType::Enum,
                 "8",
                 {"4", "8"},
                 0,
                 0,
                 "children per node: 4 (one SSE slab test) or 8 (one AVX slab test)"},
                // 4: one packet per leaf. The binary SAH stops splitting earlier when a leaf is
                // cheaper, so most leaves hold fewer.
                {"max_prims",
                 ParamType::Int,
                 "4",
                 {},
                 1,
                 BvhNode::kMaxLeafPrims,
                 "largest leaf of the binary build (SAH may stop below it); a leaf is ceil(n/4) packets"},
                {"max_depth",
                 ParamType::Int,
                 "64",
                 {},
                 0,
                 1000,
                 "binary build: nodes at this depth become leaves whatever their size"},
                // 32, not the binary BVH's 16 (Embree's binned builder uses 32 too): finer planes
                // near the root. Measured (width 8, accel_bench, 3 reps, idle machine): the
                // conference's primary rays 2.85M -> 2.24M node visits, 22.0M -> 17.3M box
                // tests, trace / Embree 1.44 -> 1.22 (width 4: 1.84 -> 1.68); bunny, igea, dragon
                // within 1% of the counts and of the time; build / Embree +0.08-0.16 (dragon
                // 1.05 -> 1.13, conference 0.90 -> 1.06, bunny 0.80 -> 0.96). 64: no better.
                {"bins", ParamType::Int, "32", {}, 2, 1024, "binned SAH bins along the split axis"},
                // 3, not the binary BVH's 1: a wide node's slab test covers several binary
                // nodes and a packet test 4 triangles, so fuller leaves pay. Measured on the
                // bunny in one accel_bench run (trace / Embree, width 8): 1 -> 1.52x, 2 -> 1.44x,
                // 3 -> 1.36x; build 1.00x -> 0.80x Embree (leaves of 3.4 triangles, not 1.8).
                {"traversal_cost",
                 ParamType::Float,
                 "3",
                 {},
                 0,
                 1e6,
                 "SAH cost of visiting a binary node, relative to isect_cost (binary build)"},
                {"isect_cost", ParamType::Float, "1", {}, 1e-6, 1e6, "SAH cost of one triangle test"},
                // Off by default for the build goal (<= 1.2x Embree): 3 passes cost the binary
                // bvh 0.5-1.2x Embree's build time more (bvh_sah_reinsert in make bench).
                {"reinsertion",
                 ParamType::Int,
                 "0",
                 {},
                 0,
                 100,
                 "passes of the reinsertion optimizer on the binary tree before the collapse (Meister & Bittner "
                 "2018; 0 = off): lower SAH cost for a longer build, the same answers"},
                {"kernel",
                 ParamType::Enum,
                 "simd",
                 {"simd", "scalar"},
                 0,
                 0,
                 "simd: the vector slab and triangle tests compiled in (scalar on a target without SSE2); "
                 "scalar: the scalar forms, identical answers (for testing and measuring the vector gain)"},
            },
            [](const ParamSet& p) { return std::make_unique<Wbvh>(p); }};
}

Wbvh::Config Wbvh::Config::from(const ParamSet& params) {
    Config c;
    c.width = params.get_enum("width") == "4" ? 4 : 8;
    c.max_prims = uint32_t(params.get_int("max_prims"));
    c.max_depth = uint32_t(params.get_int("max_depth"));
    c.bins = uint32_t(params.get_int("bins"));
    c.traversal_cost = params.get_float("traversal_cost");
    c.isect_cost = params.get_float("isect_cost");
    c.reinsertion = uint32_t(params.get_int("reinsertion"));
    c.kernel = params.get_enum("kernel") == "scalar" ? Kernel::scalar : Kernel::simd;
    return c;
}

namespace {

// The binary BVH's parameters: split=sah and the build parameters wbvh shares with it
// (reinsertion included: the optimizer runs on the binary tree, which the collapse then
// reads as it reads any binary tree — same leaves, boxes refitted).
ParamSet binary_params(const Wbvh::Config& c) {
    const std::map<std::string, std::string> given = {
        {"split", "sah"},
        {"max_prims", std::to_string(c.max_prims)},
        {"max_depth", std::to_string(c.max_depth)},
        {"bins", std::to_string(c.bins)},
        {"traversal_cost", format_param(c.traversal_cost)},
        {"isect_cost", format_param(c.isect_cost)},
        {"reinsertion", std::to_string(c.reinsertion)},
    };
    return resolve_params("bvh", Bvh::info().params, given);
}

}  // namespace

Wbvh::Wbvh(const ParamSet& params) : config_(Config::from(params)), binary_(binary_params(config_)) {}

// The collapse (see wbvh.h). Nodes are emitted depth-first: a node's inner children are
// allocated together when it is written, then built in turn.
template <int W>
void Wbvh::collapse(const FlatBvh& binary, WbvhTree<W>& out) {
    out.nodes.clear();
    out.packets.clear();
    out.depth = 0;
    out.leaves = 0;
    if (binary.empty()) return;
    out.nodes.reserve(binary.nodes.size() / 2 + 1);  // each wide node replaces at least one binary inner node
    out.packets.reserve(binary.prim_ids.size() / 2 + 1);

    struct Todo {
        uint32_t binary_node;  // inner binary node whose subtree the wide node covers (or a lone leaf root)
        uint32_t wide_node;
        uint32_t depth;
    };
    std::vector<Todo> todo;
    out.nodes.emplace_back();
    todo.push_back({0, 0, 0});
    while (!todo.empty()) {
        const Todo t = todo.back();
        todo.pop_back();
        out.depth = std::max(out.depth, t.depth);
        // The children: the binary node's two, then the largest inner child opened until W.
        uint32_t kids[W];
        int n = 0;
        const BvhNode& b = binary.nodes[t.binary_node];
        if (b.is_leaf()) {
            kids[n++] = t.binary_node;  // the whole tree is one leaf: a root with one leaf child
        } else {
            kids[n++] = t.binary_node + 1;
            kids[n++] = b.second_child();
        }
        while (n < W) {
            int open = -1;
            float open_area = -1.0f;
            for (int k = 0; k < n; ++k) {
                const BvhNode& c = binary.nodes[kids[k]];
                if (c.is_leaf()) continue;
                const float area = c.bounds.area();
                if (area > open_area) {
                    open = k;
                    open_area = area;
                }
            }
            if (open < 0) break;
            const uint32_t opened = kids[open];
            kids[open] = opened + 1;
            kids[n++] = binary.nodes[opened].second_child();
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
        for (int k = 0; k < n; ++k) {
            const BvhNode& c = binary.nodes[kids[k]];
            for (int a = 0; a < 3; ++a) {
                node.planes[a][k] = c.bounds.lower[a];
                node.planes[3 + a][k] = c.bounds.upper[a];
            }
            if (c.is_leaf()) {
                ++out.leaves;
                node.child[k] = uint32_t(out.packets.size());
                node.count[k] = c.prim_count();
                for (uint32_t first = 0; first < c.prim_count(); first += WbvhTriPacket::kLanes) {
                    WbvhTriPacket p{};
                    for (int lane = 0; lane < WbvhTriPacket::kLanes; ++lane) {
                        p.prim[lane] = kInvalidId;
                        if (first + uint32_t(lane) >= c.prim_count()) continue;
                        const uint32_t slot = c.first_prim() + first + uint32_t(lane);
                        const LeafTriangle& tri = binary.triangles[slot];
                        const Vec3 v[3] = {tri.p0, tri.p1, tri.p2};
                        for (int i = 0; i < 3; ++i)
                            for (int a = 0; a < 3; ++a) p.v[i][a][lane] = v[i][a];
                        p.prim[lane] = binary.prim_ids[slot];
                    }
                    out.packets.push_back(p);
                }
            } else {
                node.child[k] = uint32_t(out.nodes.size());
                out.nodes.emplace_back();
                todo.push_back({kids[k], node.child[k], t.depth + 1});
            }
        }
        out.nodes[t.wide_node] = node;
    }
}

void Wbvh::build(const Scene& scene) {
    binary_.build(scene);
    if (config_.width == 8) {
        collapse(binary_.tree(), tree8_);
        tree4_ = {};
    } else {
        collapse(binary_.tree(), tree4_);
        tree8_ = {};
    }
}

template <int W>
WbvhMetrics measure_wbvh(const WbvhTree<W>& tree) {
    WbvhMetrics m;
    m.nodes = tree.nodes.size();
    m.leaves = tree.leaves;
    m.packets = tree.packets.size();
    m.max_depth = tree.empty() ? 0 : tree.depth + 1;  // edges down to the deepest leaf child
    m.memory_bytes = tree.nodes.size() * sizeof(WbvhNode<W>) + tree.packets.size() * sizeof(WbvhTriPacket);
    double inner_area = 0, leaf_area = 0, root_area = 0;
    uint64_t prims = 0, children = 0;
    for (size_t i = 0; i < tree.nodes.size(); ++i) {
        const WbvhNode<W>& node = tree.nodes[i];
        Bounds3 box;
        const uint32_t n = node.child_count();
        children += n;
        for (uint32_t k = 0; k < n; ++k) {
            const Bounds3 b = node.child_bounds(int(k));
            box.extend(b);
            if (node.count[k]) {
                prims += node.count[k];
                leaf_area += double(b.area()) * node.count[k];
            }
        }
        inner_area += box.area();
        if (i == 0) root_area = box.area();
    }
    if (m.leaves) m.avg_leaf_size = double(prims) / double(m.leaves);
    if (m.nodes) m.avg_children = double(children) / double(m.nodes);
    if (m.packets) m.packet_fill = double(prims) / double(m.packets * WbvhTriPacket::kLanes);
    if (root_area > 0) m.sah_cost = (kSahCostTraversal * inner_area + kSahCostIntersection * leaf_area) / root_area;
    return m;
}

template WbvhMetrics measure_wbvh(const WbvhTree<4>&);
template WbvhMetrics measure_wbvh(const WbvhTree<8>&);

BuildStats Wbvh::build_stats() const {
    const WbvhMetrics m = config_.width == 8 ? measure_wbvh(tree8_) : measure_wbvh(tree4_);
    BuildStats s;
    s.nodes = m.nodes;
    s.leaves = m.leaves;
    s.max_depth = m.max_depth;
    s.memory_bytes = m.memory_bytes;
    if (m.leaves) s.avg_leaf_size = m.avg_leaf_size;
    s.sah_cost = m.sah_cost;
    s.extra["packets"] = double(m.packets);
    s.extra["packet_fill"] = m.packet_fill;
    s.extra["avg_children"] = m.avg_children;
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

// Closest hit (kAnyHit false): `hit` must come in empty and receives the closest hit; the
// interval shrinks to it. Any hit: the children hit are pushed in slot order, as Embree's
// any-hit traverser does, and it returns at the first triangle hit.
template <int W, bool kVector, bool kAnyHit, class C>
ACCELBENCH_BVH_HOT bool traverse(const WbvhTree<W>& tree, const Ray& ray, Hit& hit, C& c) {
    if (tree.empty()) return false;
    const WbvhRay<W, kVector> r(ray);
    if (!r.valid) return false;
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
            c.box(node.child_count());
            float tnear[W];
            uint32_t mask = wbvh_slab_test(node, r, tmin, tmax, tnear);
            if (mask == 0) goto pop;
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
                // Several: sort their keys (insertion sort, at most 8), push far to near, enter the nearest.
                // Tried and measured (issue 12, width 8): a branch-free order instead — two hit
                // children by one key compare, more by writing each straight to its stack slot by its
                // rank among the hit keys (one AVX2 compare of signed order keys per child), the same
                // visit order and counters. It ran 9-10% fewer closest-hit traversal instructions
                // (callgrind, trace/<model>/wbvh8: bunny 147.2M -> 134.5M, conference 910.4M ->
                // 816.2M) and 13% fewer simulated conditional mispredicts (bunny 433K -> 378K), but no
                // time: interleaved, load ~1.5-3, ratio to Embree bunny 1.15-1.22x before vs 1.19-1.22x
                // after, conference 1.25-1.32x vs 1.24-1.32x. Few nodes have 2+ hit children (bunny:
                // 77% of nodes with a hit have one, 15% two, 8% more); the rest of the mispredicts are
                // the inner/leaf, none/one/several-hit and pop branches, which it leaves as they are.
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
        for (uint32_t done = 0; done < cur.count; done += WbvhTriPacket::kLanes) {
            const WbvhTriPacket& p = tree.packets[cur.child + done / WbvhTriPacket::kLanes];
            const int lanes = int(std::min<uint32_t>(WbvhTriPacket::kLanes, cur.count - done));
            c.prim(uint64_t(lanes));
            const WbvhPacketHits h = wbvh_packet_test(p, lanes, r, tmin, tmax);
            if (h.mask == 0) continue;
            if constexpr (kAnyHit) {
                return true;
            } else {
                const int k = h.nearest();
                tmax = h.t[k];
                hit = {p.prim[k], h.t[k], h.u[k], h.v[k]};
            }
        }
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

template <bool kAnyHit, class C>
bool dispatch(const Wbvh& w, const Ray& ray, Hit& hit, C& c) {
    const bool vector = w.config().kernel == Wbvh::Kernel::simd;
    if (w.config().width == 8)
        return vector ? traverse<8, true, kAnyHit>(w.tree8(), ray, hit, c)
                      : traverse<8, false, kAnyHit>(w.tree8(), ray, hit, c);
    return vector ? traverse<4, true, kAnyHit>(w.tree4(), ray, hit, c)
                  : traverse<4, false, kAnyHit>(w.tree4(), ray, hit, c);
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
