// The kd-tree's closest-hit and any-hit traversals (report 4.2.2, Figures 15-16; pbrt-v3's
// KdTreeAccel::Intersect), with the optional per-ray mailbox.
#include <algorithm>
#include <array>
#include <iterator>
#include <optional>
#include <span>
#include <type_traits>

#include "accelbench/accel/kdtree/kdtree.h"
#include "accelbench/base/triangle.h"

namespace accelbench {

// ---- traversal (report 4.2.2, Figures 15-16; pbrt's KdTreeAccel::Intersect) ------------
//
// The ray is clipped to the root box, giving [t_min, t_max]. At an interior node the
// plane is crossed at t_split; the child on the side the ray comes from ("first": below
// when the direction component is positive, by its sign bit so -0.0 counts as negative)
// covers [t_min, t_split], the other [t_split, t_max]. If t_split > t_max the ray leaves
// the node before the plane (first child only); if t_split < t_min it crossed before
// entering (second only); otherwise both, first now, second pushed. A ray with a zero
// direction component gets t_split = +-inf and one child; one lying IN the plane gets
// NaN, fails both tests and visits both children over the whole range (the min/max below
// are written so that NaN yields the other argument). Choosing "first" by direction, not
// by which side the origin lies on, keeps this right for any ray.tmin.
//
// Leaves test their triangles over the whole remaining ray interval [ray.tmin, best), not
// just the leaf's [t_min, t_max]: a primitive can stick out of the leaf and be hit
// beyond it. Such a hit is kept but does not end the traversal; only a hit closer than
// the next node's t_min does (nodes leave the stack in front-to-back order).
//
// Conservative in float (Ize 2013, as intersect_box): t_split is rounded up to three
// times, so each comparison uses the interval [slack_below, slack_above](t_split) that
// holds its true value, and the ranges handed to the children are widened the same way
// (they overlap by the slack), so a node's [t_min, t_max] always contains its true range
// and a child is culled only when the ray certainly misses it. Without this the tree
// leaked rays aimed exactly at a vertex lying on two split planes (robustness case 1:
// origin (-0.5, 0.25, 0.125), direction (0.33937797, 0.443780482, 0.577046454), vertex
// at t = 1): the x-plane through the vertex gave t = 1 exactly and the y-plane through
// it t_split = 0.99999994, so the node entered at t_min = 1 beyond the x-plane dropped
// its below-y child as "crossed before entering" — the only child holding a triangle
// that contains the vertex (its y range ends on the plane, so it is classified below).

namespace {

struct StackEntry {
    uint32_t node;
    float t_min, t_max;
};

// Visits the leaves a ray passes, front to back, over [t_min, t_max] clipped to the root
// box. visit_leaf(leaf) (a reference into `nodes`) returns false to stop. keep_going(t_min)
// is asked before each popped node: closest-hit stops once its best hit lies before that
// node.
//
// The interior step is branchy on purpose: the predicted branch lets the next node's load
// start before t_split is known, where a conditional move would put the whole step (load,
// t_split, slack, compare) on the critical path of every node; branch-free forms measured
// 1.3-1.5x slower on the conference. The profile, the forms measured and the changes made:
// docs/decisions.md, kd-tree traversal.
template <class C, class VisitLeaf, class KeepGoing>
void traverse(std::span<const KdNode> nodes, const Bounds3& bounds, const Ray& ray, C& counters, VisitLeaf&& visit_leaf,
              KeepGoing&& keep_going) {
    if (nodes.empty()) return;
    const RayPrecomp rp(ray);
    counters.box();
    const BoxHit clip = intersect_box(bounds, rp, ray.tmin, ray.tmax);
    if (!clip.hit()) return;
    // tfar is already widened by intersect_box; tnear is widened here the same way.
    float t_min = slack_below(clip.tnear), t_max = clip.tfar;
    // Per-axis ray data as plain arrays: indexing a Vec3 by a run-time axis is a chain
    // of selects, and this loop indexes by the node's axis at every step.
    const float org[3] = {rp.org.x, rp.org.y, rp.org.z};
    const float inv_dir[3] = {rp.inv_dir.x, rp.inv_dir.y, rp.inv_dir.z};
    // All ones on the axes where the ray meets the above child first: first = below ^
    // ((below ^ above) & mask), one load where shifting a per-ray bit set out took three.
    const uint32_t above_first[3] = {0u - uint32_t(rp.near_is_upper[0]), 0u - uint32_t(rp.near_is_upper[1]),
                                     0u - uint32_t(rp.near_is_upper[2])};
    StackEntry stack[KdTree::kMaxDepthLimit];
    StackEntry* top = stack;
    uint32_t index = 0;
    for (;;) {
        counters.node();
        const KdNode& node = nodes[index];
        if (!node.is_leaf()) {
            const int axis = node.axis();
            const float t_split = (node.split() - org[axis]) * inv_dir[axis];
            const uint32_t below = index + 1, above = node.above_child();
            const uint32_t swap = (below ^ above) & above_first[axis];
            const uint32_t first = below ^ swap, second = above ^ swap;
            // "first only" is split_lo > t_max and "second only" split_hi < t_min. As
            // split_lo <= t_split <= split_hi (NaN compares false either way), each is the
            // plain comparison of t_split AND the one with the slack: the same decisions, but
            // the branch that chooses the child waits for t_split only, and the slack's
            // comparison is a second branch, nearly always taken with the first (as the wide
            // BVH's widened_mask, wbvh_simd.h). A mispredicted choice is found out the slack's
            // latency (abs, multiply, min, subtract) sooner: trace / Embree bunny 3.5 -> 3.3
            // (docs/decisions.md, kd-tree traversal).
            if (t_split > t_max) {
                if (slack_below(t_split) > t_max) [[likely]] {
                    index = first;
                    continue;
                }
            } else if (t_split < t_min) {
                if (slack_above(t_split) < t_min) [[likely]] {
                    index = second;
                    continue;
                }
            }
            const float split_lo = slack_below(t_split), split_hi = slack_above(t_split);
            *top++ = {second, split_lo > t_min ? split_lo : t_min, t_max};
            t_max = split_hi < t_max ? split_hi : t_max;
            index = first;
            continue;
        }
        if (!visit_leaf(node) || top == stack) return;
        --top;
        index = top->node;
        t_min = top->t_min;
        t_max = top->t_max;
        if (!keep_going(t_min)) return;
    }
}

}  // namespace

const uint32_t* KdTree::leaf_prims(const KdNode& leaf, uint32_t& count) const {
    count = leaf.prim_count();
    return count == 1 ? leaf.single_prim_run() : prim_indices_.data() + leaf.prim_offset();
}

// Inlined into each leaf loop (GCC otherwise calls it: the call and its argument set-up cost
// ~10 instructions per test).
[[gnu::always_inline]] inline bool KdTree::hit_triangle(const WatertightRay& wr, uint32_t prim, float tmin, float tmax,
                                                        Hit& hit) const {
    const std::array<Vec3, 3>& tri = corners_[prim];
    if (!intersect_triangle(wr, tri[0], tri[1], tri[2], tmin, tmax, hit.t, hit.u, hit.v)) return false;
    hit.prim = prim;
    return true;
}

// The triangles a ray tested, in a direct-mapped table indexed by the low bits of the
// triangle's index: a triangle evicts only one whose index shares them, and leaves along
// a ray share triangles mostly with the leaves just before them (the triangle straddles
// their common plane), so the few tests a ray makes rarely collide (an eviction only
// costs a repeated test, never an answer). One scalar load, compare and store per test;
// an 8-entry ring searched with one vector compare was slower (docs/decisions.md).
class Mailbox {
public:
    Mailbox() { std::fill(std::begin(ids_), std::end(ids_), kInvalidId); }
    // Whether `prim` was tested already; if not, remembers it.
    bool seen(uint32_t prim) {
        uint32_t& slot = ids_[prim & (kSize - 1)];
        const bool found = slot == prim;
        slot = prim;
        return found;
    }

private:
    static constexpr uint32_t kSize = 64;
    uint32_t ids_[kSize];
};

// No mailbox: never seen.
struct NoMailbox {
    static constexpr bool seen(uint32_t) { return false; }
};

// The leaf loop both queries share: each of a leaf's triangles the mailbox has not seen is
// counted and handed to test(prim), the shear constants made first if this is the ray's
// first leaf with a triangle; stops (returns false) when test returns false.
template <class Mailbox, class C, class Test>
inline bool for_untested_triangles(const uint32_t* prims, uint32_t count, const Ray& ray,
                                   std::optional<WatertightRay>& wr, Mailbox& mailbox, C& counters, Test&& test) {
    if (count != 0 && !wr) wr.emplace(ray);
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t prim = prims[i];
        if (mailbox.seen(prim)) continue;
        counters.prim();
        if (!test(prim)) return false;
    }
    return true;
}

// A leaf tests its triangles one at a time: SSE packets of four cost a triangle copy per
// reference (docs/decisions.md, kd-tree, "SSE packet leaves").
template <bool kMailbox, class C>
void KdTree::intersect_with(const Ray& ray, Hit& hit, C& counters) const {
    // The shear constants are made at the first leaf with a triangle, not before the
    // traversal: many rays (the bunny's primary rays that pass beside it) never get there
    // (bunny closest-hit instructions -9%).
    std::optional<WatertightRay> wr;
    float best = ray.tmax;
    std::conditional_t<kMailbox, Mailbox, NoMailbox> mailbox;
    traverse(
        nodes_, bounds_, ray, counters,
        [&](const KdNode& leaf) {
            uint32_t count;
            const uint32_t* prims = leaf_prims(leaf, count);
            return for_untested_triangles(prims, count, ray, wr, mailbox, counters, [&](uint32_t prim) {
                if (hit_triangle(*wr, prim, ray.tmin, best, hit)) best = hit.t;
                return true;
            });
        },
        // next_t_min is a lower bound of the node's true entry distance, but a hit in it
        // is a computed t that may round below its true value: stop only when the best
        // hit lies before that node by more than the slack, so a hit at the node's
        // boundary (a vertex on its plane) is never skipped for a farther one.
        [&](float next_t_min) { return !(best < next_t_min && best < slack_below(next_t_min)); });
}

template <bool kMailbox, class C>
bool KdTree::occluded_with(const Ray& ray, C& counters) const {
    std::optional<WatertightRay> wr;  // made at the first leaf with a triangle, as above
    bool found = false;
    std::conditional_t<kMailbox, Mailbox, NoMailbox> mailbox;
    traverse(
        nodes_, bounds_, ray, counters,
        [&](const KdNode& leaf) {
            Hit scratch;
            uint32_t count;
            const uint32_t* prims = leaf_prims(leaf, count);
            return for_untested_triangles(prims, count, ray, wr, mailbox, counters, [&](uint32_t prim) {
                if (!hit_triangle(*wr, prim, ray.tmin, ray.tmax, scratch)) return true;
                found = true;
                return false;  // stop at the first hit
            });
        },
        [](float) { return true; });
    return found;
}

template <class C>
void KdTree::intersect(const Ray& ray, Hit& hit, C& counters) const {
    if (config_.mailbox) intersect_with<true>(ray, hit, counters);
    else intersect_with<false>(ray, hit, counters);
}

template <class C>
bool KdTree::occluded(const Ray& ray, C& counters) const {
    return config_.mailbox ? occluded_with<true>(ray, counters) : occluded_with<false>(ray, counters);
}

ACCELBENCH_INSTANTIATE_RAY_QUERIES(KdTree);

}  // namespace accelbench
