// Traversal of a FlatBvh (bvh_node.h), shared by the top-down BVH and the LBVH: the
// report uses one traversal for both (section 3.2: "the same traversal algorithm used in
// the BVH will be utilized for LBVH"), and so do we, so that differences between the two
// rows come from the trees alone.
//
// Two algorithms, chosen by the structure's `traversal` parameter:
//
//  ordered  What production tracers do (pbrt-v4's BVHAggregate::Intersect, Embree,
//           madmann91/bvh): iterative with an explicit stack; at an inner node both
//           children's boxes are tested and the nearer one (by entry distance) is entered
//           first, the other is pushed with its entry distance; a popped node whose entry
//           distance lies beyond the closest hit so far is skipped, and every box test is
//           clipped to the closest hit. Any-hit queries stop at the first hit.
//
//  report   The report's Algorithm 1 (section 2.2.3): visit every node whose box the ray
//           hits (left child, then right child), collect the primitives of every leaf
//           reached into a hit list, and take the nearest of them. Box tests are never
//           clipped to a hit found earlier, so it visits exactly the nodes Algorithm 1
//           visits. The hit list is not materialised: each collected primitive is tested
//           when it is collected and the nearest is kept, which tests the same primitives
//           and returns the same one (the first of equally near hits in visiting order)
//           without a per-ray allocation. Any-hit queries may stop at the first hit.
//
// Both count with the shared counters: c.node() per node entered, c.box() per ray/box
// slab test, c.prim() per ray/triangle test.
//
// Why this loop has the shape it has: the report's rows must keep every box decision and
// count, and on these trees the loop waits on the node-to-node chain (load, test, branch),
// not on instructions or memory. The forms measured and not adopted (FMA slabs, two
// children per vector, branch-free child order, other node layouts, a stack without entry
// distances) are in docs/decisions.md, "Binary BVH traversal".
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>

#include "accelbench/accel/bvh/bvh_packet_leaves.h"
#include "accelbench/accel/bvh/flat_bvh.h"
#include "accelbench/accel/bvh/wbvh_simd.h"
#include "accelbench/base/geometry.h"
#include "accelbench/base/param_table.h"
#include "accelbench/base/triangle.h"

namespace accelbench {

// The per-ray loops inline everything they call (box and triangle tests): GCC otherwise
// keeps intersect_box out of line in these large loops, and the call costs more than
// the slab test itself.
#if defined(__GNUC__)
#define ACCELBENCH_BVH_HOT [[gnu::flatten]]
#else
#define ACCELBENCH_BVH_HOT
#endif

enum class BvhTraversal { ordered, report };
inline constexpr std::array<std::string_view, 2> kBvhTraversalNames = {"ordered", "report"};  // the enum's order

// The `traversal` parameter as both BVH structures declare it.
template <class Config>
ParamRow<Config> bvh_traversal_param(BvhTraversal Config::*member) {
    return enum_param("traversal", member, kBvhTraversalNames,
                      "ordered: near child first, clipped to the closest hit (pbrt/Embree); "
                      "report: the report's Algorithm 1 (every hit box, nearest of the collected hits)");
}

// The stack of nodes still to visit. Both traversals push at most one node per level
// below the root (the sibling of the child they descend into), so depth + 1 entries
// always suffice: the stack is sized from the finished tree's depth and cannot overflow,
// whatever the builder did. Trees up to 64 levels deep (all balanced ones) use the inline
// array; deeper ones allocate once per ray.
//
// The traversal loops keep the top of the stack in a local pointer (Cursor) rather than
// in this object: a count held here would be written through the same kind of pointer
// as the entries, so the compiler would have to reload it from memory after every push.
class BvhTraversalStack {
public:
    struct Entry {
        uint32_t node;
        float tnear;  // entry distance into the node's box (ordered traversal)
    };

    explicit BvhTraversalStack(uint32_t tree_depth) {
        if (tree_depth + 1 > kInline) {
            heap_ = std::make_unique<Entry[]>(size_t(tree_depth) + 1);
            data_ = heap_.get();
        }
    }
    BvhTraversalStack(const BvhTraversalStack&) = delete;
    BvhTraversalStack& operator=(const BvhTraversalStack&) = delete;

    // The stack's top, a value the traversal keeps in a register.
    class Cursor {
    public:
        explicit Cursor(BvhTraversalStack& s) : bottom_(s.data_), top_(s.data_) {}
        bool empty() const { return top_ == bottom_; }
        void push(uint32_t node, float tnear = 0.0f) { *top_++ = {node, tnear}; }
        Entry pop() { return *--top_; }

    private:
        Entry* bottom_;
        Entry* top_;
    };

private:
    static constexpr uint32_t kInline = 64;
    Entry inline_[kInline];
    std::unique_ptr<Entry[]> heap_;
    Entry* data_ = inline_;
};

// The leaf tests the traversals are instantiated with. Each is made per ray (its per-ray
// constants) once the root box is hit, and offers
//   test<kAnyHit>(index, leaf, tmin, tmax, hit, c)
// over the leaf's triangles against [tmin, tmax), index being the leaf's node index and leaf
// the node. Closest hit (kAnyHit false): on a closer hit writes `hit`, shrinks tmax and
// returns true. Any hit: returns true at the first hit, leaving tmax and `hit` as they are.

// One triangle at a time (intersect_triangle), read from the tree's slots: the report rows'
// test (their leaves hold one triangle) and `bvh leaf_test=scalar`.
class ScalarLeafTest {
public:
    using Leaves = FlatBvh;
    ScalarLeafTest(const FlatBvh& bvh, const Ray& ray) : bvh_(bvh), wr_(ray) {}
    // intersect_triangle answers an invalid ray itself (no hit), after the traversal has
    // visited and counted its nodes as for any other ray.
    static constexpr bool valid() { return true; }

    template <bool kAnyHit, class C>
    bool test(uint32_t, const BvhNode& leaf, float tmin, float& tmax, Hit& hit, C& c) const {
        bool found = false;
        const uint32_t end = leaf.first_prim() + leaf.prim_count();
        for (uint32_t slot = leaf.first_prim(); slot < end; ++slot) {
            c.prim();
            const LeafTriangle& tri = bvh_.triangles[slot];
            float t, u, v;
            if (!intersect_triangle(wr_, tri.p0, tri.p1, tri.p2, tmin, tmax, t, u, v)) continue;
            if constexpr (kAnyHit) return true;
            tmax = t;
            hit = {bvh_.prim_ids[slot], t, u, v};
            found = true;
        }
        return found;
    }

private:
    const FlatBvh& bvh_;
    WatertightRay wr_;
};

// Four triangles per test (bvh_packet_leaves.h, wbvh_leaf_test): `bvh leaf_test=packet`, what
// auto picks for split=sah's default leaves. The closest hit is the scalar loop's (the
// nearest, and of equally near ones the first in slot order). Counts: c.prim() per lane
// tested, so an any-hit search that stops in a packet counts all of that packet's lanes,
// where the scalar loop stops at the hit.
class PacketLeafTest {
public:
    using Leaves = BvhPacketLeaves;
    PacketLeafTest(const BvhPacketLeaves& leaves, const Ray& ray)
        : packets_(leaves.packets.data()), first_packet_(leaves.first_packet.data()), r_(ray) {}
    // The vector test needs a valid ray: an invalid one (which hits nothing) ends at the root,
    // as in the wide BVH.
    bool valid() const { return r_.valid; }

    template <bool kAnyHit, class C>
    bool test(uint32_t index, const BvhNode& leaf, float tmin, float& tmax, Hit& hit, C& c) const {
        return wbvh_leaf_test<kAnyHit>(packets_ + first_packet_[index], leaf.prim_count(), r_, tmin, tmax, hit, c);
    }

private:
    // The arrays' starts, held by value: through a reference to the vectors, GCC reloaded
    // both data pointers at every leaf.
    const WbvhTriPacket* packets_;
    const uint32_t* first_packet_;
    WbvhRay<4, true> r_;  // the SSE form where it is compiled in
};

// Ordered traversal. Closest hit (kAnyHit false): `hit` must come in empty (Hit{}) and
// receives the closest hit; the search interval shrinks to it. Any hit (kAnyHit true):
// returns at the first hit found (the near-first order costs one comparison and tends to
// meet occluders early).
template <bool kAnyHit, class LeafTest, class C>
ACCELBENCH_BVH_HOT bool traverse_bvh_ordered(const FlatBvh& bvh, const typename LeafTest::Leaves& leaves,
                                             const Ray& ray, Hit& hit, C& c) {
    if (bvh.empty()) return false;
    const RayPrecomp rp(ray);
    float tmax = ray.tmax;  // the closest hit so far: nothing beyond it matters
    c.box();
    if (!intersect_box(bvh.nodes[0].bounds, rp, ray.tmin, tmax).hit()) return false;
    const LeafTest leaf_test(leaves, ray);
    if (!leaf_test.valid()) return false;
    BvhTraversalStack storage(bvh.depth);
    BvhTraversalStack::Cursor stack(storage);
    uint32_t index = 0;
    for (;;) {
        c.node();
        const BvhNode& node = bvh.nodes[index];
        if (!node.is_leaf()) {
            uint32_t near = index + 1, far = node.second_child();
            c.box(2);
            BoxHit hn = intersect_box(bvh.nodes[near].bounds, rp, ray.tmin, tmax);
            BoxHit hf = intersect_box(bvh.nodes[far].bounds, rp, ray.tmin, tmax);
            if (hn.hit() && hf.hit()) {
                if (hf.tnear < hn.tnear) {
                    std::swap(near, far);
                    std::swap(hn, hf);
                }
                stack.push(far, hf.tnear);
                index = near;
                continue;
            }
            if (hn.hit() || hf.hit()) {
                index = hn.hit() ? near : far;
                continue;
            }
        } else if (leaf_test.template test<kAnyHit>(index, node, ray.tmin, tmax, hit, c) && kAnyHit) {
            return true;
        }
        // Next: the nearest pushed node the ray can still reach before the closest hit.
        for (;;) {
            if (stack.empty()) return hit.found();
            const BvhTraversalStack::Entry e = stack.pop();
            if (e.tnear <= tmax) {
                index = e.node;
                break;
            }
        }
    }
}

// The report's Algorithm 1: visits every node whose box the ray hits over its whole
// interval, left child before right child, and calls leaf(index, node) for each leaf
// reached; stops as soon as leaf() returns true. Returns whether it stopped.
template <class C, class Leaf>
ACCELBENCH_BVH_HOT bool visit_bvh_report(const FlatBvh& bvh, const Ray& ray, C& c, Leaf&& leaf) {
    if (bvh.empty()) return false;
    const RayPrecomp rp(ray);
    BvhTraversalStack storage(bvh.depth);
    BvhTraversalStack::Cursor stack(storage);
    uint32_t index = 0;
    for (;;) {
        c.node();
        c.box();
        const BvhNode& node = bvh.nodes[index];
        if (intersect_box(node.bounds, rp, ray.tmin, ray.tmax).hit()) {
            if (!node.is_leaf()) {
                stack.push(node.second_child());
                index = index + 1;
                continue;
            }
            if (leaf(index, node)) return true;
        }
        if (stack.empty()) return false;
        index = stack.pop().node;
    }
}

// Algorithm 1, closest hit: the nearest of the primitives of every leaf reached.
template <class LeafTest, class C>
ACCELBENCH_BVH_HOT void intersect_bvh_report(const FlatBvh& bvh, const typename LeafTest::Leaves& leaves,
                                             const Ray& ray, Hit& hit, C& c) {
    const LeafTest leaf_test(leaves, ray);
    if (!leaf_test.valid()) return;
    float nearest = ray.tmax;  // nearest hit among the primitives collected so far
    visit_bvh_report(bvh, ray, c, [&](uint32_t index, const BvhNode& leaf) {
        leaf_test.template test<false>(index, leaf, ray.tmin, nearest, hit, c);
        return false;
    });
}

// Algorithm 1, any hit: the same visiting order, stopping at the first hit.
template <class LeafTest, class C>
ACCELBENCH_BVH_HOT bool occluded_bvh_report(const FlatBvh& bvh, const typename LeafTest::Leaves& leaves, const Ray& ray,
                                            C& c) {
    const LeafTest leaf_test(leaves, ray);
    if (!leaf_test.valid()) return false;
    float tmax = ray.tmax;  // an any-hit test leaves it as it is
    Hit unused;
    return visit_bvh_report(bvh, ray, c, [&](uint32_t index, const BvhNode& leaf) {
        return leaf_test.template test<true>(index, leaf, ray.tmin, tmax, unused, c);
    });
}

// Dispatch by the structure's `traversal` parameter (one predictable branch per ray), with
// the leaf test LeafTest over `leaves`.
template <class LeafTest, class C>
inline void intersect_bvh(BvhTraversal traversal, const FlatBvh& bvh, const typename LeafTest::Leaves& leaves,
                          const Ray& ray, Hit& hit, C& c) {
    if (traversal == BvhTraversal::ordered) traverse_bvh_ordered<false, LeafTest>(bvh, leaves, ray, hit, c);
    else intersect_bvh_report<LeafTest>(bvh, leaves, ray, hit, c);
}

template <class LeafTest, class C>
inline bool occluded_bvh(BvhTraversal traversal, const FlatBvh& bvh, const typename LeafTest::Leaves& leaves,
                         const Ray& ray, C& c) {
    if (traversal == BvhTraversal::ordered) {
        Hit unused;
        return traverse_bvh_ordered<true, LeafTest>(bvh, leaves, ray, unused, c);
    }
    return occluded_bvh_report<LeafTest>(bvh, leaves, ray, c);
}

// The same with the scalar leaf test over the tree's own slots (the LBVH, tests).
template <class C>
inline void intersect_bvh(BvhTraversal traversal, const FlatBvh& bvh, const Ray& ray, Hit& hit, C& c) {
    intersect_bvh<ScalarLeafTest>(traversal, bvh, bvh, ray, hit, c);
}
template <class C>
inline bool occluded_bvh(BvhTraversal traversal, const FlatBvh& bvh, const Ray& ray, C& c) {
    return occluded_bvh<ScalarLeafTest>(traversal, bvh, bvh, ray, c);
}

}  // namespace accelbench
