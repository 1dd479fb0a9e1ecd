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
// What was measured to make the ordered loop tighter (callgrind, the bunny's 320x240
// primary + shadow render, counts unchanged by each): the box test's per-axis choice
// between the two planes was a third of its instructions — an index per ray removes it
// (intersect_box), and the triangle test's run-time-axis Vec3 reads likewise
// (intersect_triangle): 16-17% fewer instructions for bvh and lbvh. Not adopted, because
// every box decision and count of the report's rows must stay as it is: one FMA per slab
// on precomputed origin * (1 / dir) (bvh v2's form: it rounds differently, and without
// -march it is a multiply and an add, no fewer than subtract and multiply) and a stack
// without entry distances (popped nodes beyond the closest hit would be entered and
// counted). A 4-lane SSE form of intersect_box with identical decisions gave no fewer
// instructions (the SSE2 blends and lane reductions cost what the loads saved).
//
// Session 4 measured the memory side (callgrind --cache-sim=yes with the simulated last
// level set to this machine's 512 KiB L2; then accel_bench against Embree, interleaved,
// under a load of 4-7 on the 2 cores), all with unchanged counts, and adopted none:
//  - a sibling-pair node order (bvh v2's: both children of a node adjacent, each pair one
//    64-byte-aligned line, the parent holding the first child's index): conference lbvh
//    D1 read misses -41% (closest hit) / -24% (any hit), but L2 misses only -4%, against
//    1234M + 1035M instructions, and trace / Embree moved by noise or worse (conference
//    lbvh 3.6 -> 3.35, bvh sah 2.8 -> 2.85; dragon bvh sah 2.21 -> 2.4, lbvh 2.85 -> 3.05);
//  - a 64-byte-aligned node array in today's order (malloc's 16-byte alignment splits
//    every other node over two lines): no change beyond noise on the dragon or conference;
//  - a branch-free child order with a conditional push (the both/one/none branch is a
//    fifth of the program's simulated mispredictions): +12% instructions, not fewer
//    mispredictions, conference trace / Embree 2.8 -> 3.2 (bvh sah), 3.6 -> 4.0 (lbvh).
// What the profile shows instead: these coherent rays miss in L1 under twice each
// (bunny: 0.6M misses for 0.36M rays of 600-3000 instructions), so the gap to Embree is
// instructions and their dependency chain, not memory. Per ray on the bunny (bvh sah):
// primary 610 instructions (Embree's rtcIntersect1 312), shadow 3070 (Embree's
// rtcOccluded1 757); a shadow ray starts on the surface inside every box around its
// origin, and a binary tree with one-triangle leaves has twice the levels and four times
// the leaves of Embree's 4-wide tree with 4-triangle leaves there — a property of the
// tree (node width, leaf size), which the report's rows must keep.
//
// Session 6 measured, and did not adopt, two children per vector (branch s6-pair): a 64-byte
// record per inner node holding both children's boxes structure-of-arrays, one 4-lane SSE
// slab test for both (near planes in lanes 0-1, far planes in lanes 2-3 multiplied by
// -(1 / dir), so one MAXPS chain gives the entry distances and the negated exit distances,
// bit for bit intersect_box's; the root's box in a record of its own). Decisions, answers and
// counts identical (a test compared both forms on every ray of the bunny, the procedural
// scenes and the extreme-case catalogue, every split and the LBVH). Callgrind, one trace
// (640x480 primary + shadow), closest / any hit: bunny bvh sah 191.9M / 163.7M -> 153.2M /
// 117.5M, lbvh 226.4M / 188.4M -> 177.9M / 133.9M; conference bvh sah 1092M / 748M -> 861M /
// 517M, lbvh 1234M / 1035M -> 1014M / 717M (-18% to -31%). Time did not follow (accel_bench
// A/B, trace / Embree, two rounds, load 3-6): bunny bvh sah 1.99 -> 1.97 | 1.97 -> 1.92,
// median 2.43 -> 2.41 | 2.43 -> 2.41, lbvh 2.31 -> 2.28 | 2.31 -> 2.32; conference bvh sah
// 2.44 -> 2.44 | 2.49 -> 2.34, lbvh 3.12 -> 2.93 | 3.26 -> 2.92, median 5.56 -> 6.16 | 5.71 ->
// 6.02 (slower in both rounds, not explained). The likely reason, not measured apart: the
// vector test's chain (three MAXPS, then the widening and the compare) is as long as each of
// the two scalar tests' chains, which run side by side — the loop is bound by the node-to-node
// latency, not by instructions. And the records cost node memory x2 and a pass after every
// build: build / Embree bvh median bunny 0.46 -> 0.55 | 0.45 -> 0.51, lbvh bunny 0.20 -> 0.26
// | 0.19 -> 0.23, against build goals of 0.5 and 0.25.
//
// Session 8 measured, and did not adopt, the wide BVH's widened_mask (wbvh_simd.h) here: both
// children's hit decisions taken from the unwidened comparisons (tnear <= tfar before the
// 2 gamma(3) widening) with a rarely taken branch to the widened ones when they differ — the
// same decisions and counts (every ray's totals on the bunny and the conference, ctest), the
// slack's latency off the chain. The kd-tree's version of it gained 4-6% (kdtree.cpp); here,
// trace / Embree, interleaved A/B, four rounds: dragon bvh sah 2.11 2.12 2.11 2.11 -> 2.24 2.52
// 2.26 2.24, median 2.65 2.68 2.73 2.72 -> 2.86 3.02 2.91 2.83; bunny bvh sah 1.81 1.84 ->
// 1.73 1.84, conference within its noise (median 4.55-5.85 either way). Slower where the
// tree is largest; not analysed further (the combined mask replaces the short-circuit
// branches GCC laid out for hn.hit() && hf.hit()).
//
// Session 9 measured, and did not adopt, two forms with fewer simulated mispredictions (the
// `hn.hit() && hf.hit()` branch is 2.69M of the bunny's 6.44M in callgrind's branch
// simulation, bvh sah, closest + any hit, two renders); both had identical counts, and both
// were timed against the binary before triangle.h's one-branch outside test, which the new
// binaries had (so their true loss is larger than the figures):
//  - branch-free: both hit children pushed with conditional stack increments (the first
//    with entry distance -inf, so it is always entered), the order by masks, the next node
//    always popped: 6.44M -> 3.41M mispredictions, +12% instructions, and trace / Embree
//    1.3-2.3x slower (bunny bvh sah 1.78 -> 2.5, conference median 5 -> 11): every step's
//    next index then waits for both box tests and a store-to-load round trip, where the
//    predicted branch lets the next node's loads start at once (the kd-tree's note, kdtree.cpp).
//  - one 2-bit hit mask, then `== 3` (both) and `!= 0` (one): 6.44M -> 5.08M, +3%
//    instructions, and 15-60% slower on all four models (bunny bvh sah 1.90 -> 2.35, dragon
//    2.18 -> 2.74, conference median 5.3 -> 8.4): the hardware predicts GCC's two short-circuit
//    branches far better than callgrind's model does, and the mask waits for both tests.
// Callgrind's misprediction counts are no guide to this loop's time on this machine.
//
// Session 10 measured the box-test form apart (the first suspect), and did not adopt
// it: bvh v2's one FMA per slab, plane * inv + (-origin * inv), made conservative without any
// per-box cost. Per ray: the inverse scaled by 1 -+ 2^-22 for near and far planes, -origin *
// that rounded outward by at least an ulp, so each near distance errs below and each far
// distance above its true value whenever it is not negative (the FMA rounds once; the scaled
// inverse covers its rounding and the reciprocal's); no far widening then. Valid for rays with
// tmin >= 0 and every |1 / dir| <= 2^66 (no product overflows below kMaxCoordinate), others
// kept intersect_box. The closest-hit loop's instructions fell 27% (callgrind, bunny bvh sah
// 640x480 render: 124.1M -> 90.1M; any hit 81.3M -> 80.9M), and the loop had its 18 FMAs, but
// trace / Embree did not move (interleaved A/B, three rounds, bunny: bvh sah 1.65 1.71 1.66 ->
// 1.70 1.72 1.74, median 2.14 2.12 2.20 -> 2.15 2.15 2.15, lbvh 2.02 2.02 2.06 -> 2.02 2.08
// 2.05; dragon and conference, two rounds, within noise: bvh sah 1.88 1.97 -> 1.88 1.93,
// conference median 4.53 4.71 -> 4.34 4.35), with a per-ray choice of form or without it. It
// also admits more boxes where flat boxes meet grazing rays: conference bvh median primary
// prim tests +2.4% (bunny +0.01%), which would change the report rows' counts. As with the
// forms above: the loop waits on the node-to-node chain (load, test, branch), not on
// instructions. (Session 9 had timed bvh v2's unconservative form, no widening at all, 10-20%
// faster on these trees; why the conservative form keeps none of that was not analysed.)
// Also measured in session 10, and not adopted: `bvh split=sah`'s leaves of two or more
// triangles tested as 4-lane packets with the wide BVH's SSE watertight test (wbvh_simd.h,
// whose lanes answer as intersect_triangle; wbvh_test checks it), from packets made in
// FlatBvh::finalize: trace / Embree bunny 1.67 1.63 1.69 -> 1.80 1.70 1.74, conference 2.01
// 1.92 -> 1.99 2.02. It also counted every used lane of an any-hit packet, where the scalar
// loop stops at the hit (bunny shadow prim tests 235,584 -> 240,340). The SAH leaves are small
// (the bunny's 69,451 triangles in 38,016 leaves, 1.8 a leaf), so a packet is half empty; that
// the vector ray's per-ray constants then cost what the lanes save is likely, not measured.
// Session 11 adopted the packets together with SAH leaves fit to fill them (traversal_cost 4,
// 5.4 triangles a leaf on the bunny): PacketLeafTest below, bvh_packet_leaves.h for the figures.
// And the stack apart (bvh v2's: node indices only, every popped node entered): bunny primary
// node visits +8.7% (1,558,153 -> 1,693,775, bvh sah; shadow rays unchanged: an any-hit ray's
// interval never shrinks, so no popped node ever lies beyond it), trace / Embree bvh sah 1.66 1.63 1.65 -> 1.66 1.68 1.71, median 2.15 2.15
// 2.17 -> 2.16 2.16 2.26, lbvh 2.00 1.99 2.01 -> 2.04 2.09 2.07: the distances pay for
// themselves, and the report rows' counts stay as they are.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "accelbench/accel/bvh/bvh_packet_leaves.h"
#include "accelbench/accel/bvh/flat_bvh.h"
#include "accelbench/accel/bvh/wbvh_simd.h"
#include "accelbench/base/geometry.h"
#include "accelbench/base/params.h"
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

// The `traversal` parameter as both BVH structures declare it, and its value.
inline ParamSpec bvh_traversal_param() {
    return {"traversal",
            ParamType::Enum,
            "ordered",
            {"ordered", "report"},
            0,
            0,
            "ordered: near child first, clipped to the closest hit (pbrt/Embree); "
            "report: the report's Algorithm 1 (every hit box, nearest of the collected hits)"};
}
inline BvhTraversal bvh_traversal_from(const ParamSet& params) {
    return params.get_enum("traversal") == "report" ? BvhTraversal::report : BvhTraversal::ordered;
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
