#include "accelbench/accel/baseline/reference.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "accelbench/accel/tree_tally.h"
#include "accelbench/base/exact_predicates.h"
#include "accelbench/base/param_table.h"

namespace accelbench {

namespace {

// The parameters, each once: its row and its Config member, whose initializer is the default.
const ParamTable<ReferenceAccel::Config>& reference_params() {
    using C = ReferenceAccel::Config;
    static const ParamTable<C> rows = {
        int_param("leaf_size", &C::leaf_size, 1, 64, "largest number of triangles in a leaf"),
    };
    return rows;
}

}  // namespace

AcceleratorInfo ReferenceAccel::info() {
    return {"reference",
            "ground truth for the error columns: object-median BVH, double precision, exact hit/miss decision, "
            "conservative box tests; never timed",
            reference_params().specs(),
            [](const ParamSet& p) { return std::make_unique<ReferenceAccel>(Config::from(p)); },
            fixed_label("reference")};
}

ReferenceAccel::Config ReferenceAccel::Config::from(const ParamSet& p) { return reference_params().from(p); }

namespace {

constexpr double kUnitRoundoff = std::numeric_limits<double>::epsilon() * 0.5;
constexpr double gamma(int n) { return n * kUnitRoundoff / (1 - n * kUnitRoundoff); }

// Ize 2013: each slab distance (plane - origin) * (1 / dir) carries three roundings, so
// near and far distances are each within gamma(3) of the true values; enlarging the far
// one by 2 gamma(3) of its magnitude makes "near <= far" hold whenever it holds exactly.
constexpr double kBoxSlackDouble = 2 * gamma(3);
inline double enlarge(double t) { return std::isinf(t) ? t : t + kBoxSlackDouble * std::fabs(t); }

// Forward error bound of an edge function evaluated in double from float inputs, relative
// to its permanent (the same sum with every term's absolute value): 7 roundings in all
// (the two differences, the product, the cross-product subtraction, the product with the
// direction, two additions) give gamma(7) ~ 7.8e-16; 1e-14 leaves a wide margin.
constexpr double kEdgeErrorBound = 1e-14;
static_assert(kEdgeErrorBound > 2 * gamma(7));

// A ray converted to double exactly, with what the box and triangle tests reuse.
struct RayD {
    double o[3], d[3], inv[3];
    int near_is_upper[3];
    int k = 2;  // dominant axis of the direction, where t is read off
    double tmin, tmax;
    bool valid;

    explicit RayD(const Ray& r) : tmin(r.tmin), tmax(r.tmax) {
        valid = is_valid_ray(r);
        for (int a = 0; a < 3; ++a) {
            o[a] = r.org[a];
            d[a] = r.dir[a];
            // 1 / +-0 is +-inf, and the sign bit then picks the near plane, as in geometry.h.
            inv[a] = d[a] != 0.0 ? 1.0 / d[a] : std::copysign(std::numeric_limits<double>::infinity(), d[a]);
            near_is_upper[a] = std::signbit(inv[a]) ? 1 : 0;
        }
        k = max_axis(Vec3{std::fabs(r.dir.x), std::fabs(r.dir.y), std::fabs(r.dir.z)});
    }
};

// Conservative slab test in double over [tmin, tmax]; on a hit returns the entry distance
// in `tnear`. A NaN (origin on a plane of an axis the ray does not move along) never
// replaces the interval: the ray counts as inside that slab.
inline bool intersect_box_conservative(const Bounds3& b, const RayD& r, double tmin, double tmax, double& tnear) {
    for (int a = 0; a < 3; ++a) {
        const double near_plane = r.near_is_upper[a] ? b.upper[a] : b.lower[a];
        const double far_plane = r.near_is_upper[a] ? b.lower[a] : b.upper[a];
        const double tn = (near_plane - r.o[a]) * r.inv[a];
        const double tf = (far_plane - r.o[a]) * r.inv[a];
        tmin = tn > tmin ? tn : tmin;
        tmax = tf < tmax ? tf : tmax;
    }
    tnear = tmin;
    return tmin <= enlarge(tmax);
}

// The edge function of the edge (pj, pl), i.e. the weight of the opposite vertex:
// d . (qj x ql). Evaluated in double; recomputed exactly when the double value cannot be
// trusted for its sign.
inline double edge_function(const RayD& r, const double (&p)[3][3], const double (&q)[3][3], int j, int l) {
    double value = 0.0, permanent = 0.0;
    for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        const double x = q[j][b] * q[l][c], y = q[j][c] * q[l][b];
        value += r.d[a] * (x - y);
        permanent += std::fabs(r.d[a]) * (std::fabs(x) + std::fabs(y));
    }
    if (std::fabs(value) > kEdgeErrorBound * permanent) return value;
    const exact::Expansion e = exact::edge_volume(r.d, r.o, p[j], p[l]);
    const int s = exact::sign(e);
    return s == 0 ? 0.0 : std::copysign(std::fabs(exact::estimate(e)), double(s));
}

bool intersect_triangle_double(const RayD& r, Vec3 p0, Vec3 p1, Vec3 p2, ReferenceHit& hit) {
    const double p[3][3] = {{p0.x, p0.y, p0.z}, {p1.x, p1.y, p1.z}, {p2.x, p2.y, p2.z}};
    double q[3][3];
    for (int i = 0; i < 3; ++i)
        for (int a = 0; a < 3; ++a) q[i][a] = p[i][a] - r.o[a];
    const double e0 = edge_function(r, p, q, 1, 2);
    const double e1 = edge_function(r, p, q, 2, 0);
    const double e2 = edge_function(r, p, q, 0, 1);
    // The signs are exact: a mixed sign means the line passes outside an edge.
    if ((e0 < 0 || e1 < 0 || e2 < 0) && (e0 > 0 || e1 > 0 || e2 > 0)) return false;
    const double det = e0 + e1 + e2;  // all of one sign, so zero only if all are zero
    if (det == 0.0) return false;
    // The hit point is sum(e_i p_i) / det; t is its distance from the origin along the
    // dominant axis of the direction.
    const int k = r.k;
    const double t = (e0 * q[0][k] + e1 * q[1][k] + e2 * q[2][k]) / (det * r.d[k]);
    if (!(t >= r.tmin && t < r.tmax)) return false;
    hit.t = t;
    hit.u = e1 / det;
    hit.v = e2 / det;
    return true;
}

}  // namespace

bool reference_intersect_triangle(const Ray& ray, Vec3 p0, Vec3 p1, Vec3 p2, ReferenceHit& hit) {
    const RayD r(ray);
    return r.valid && intersect_triangle_double(r, p0, p1, p2, hit);
}

void ReferenceAccel::build(const Scene& scene) {
    const size_t n = scene.triangle_count();
    if (scene.prim_bounds.size() != n)
        throw std::runtime_error("reference: scene '" + scene.name + "' is not finalized (call Scene::finalize())");
    if (n >= size_t(kInvalidId))
        throw std::runtime_error("reference: scene '" + scene.name + "' has " + std::to_string(n) +
                                 " triangles, more than 32-bit primitive ids can name");
    scene_ = &scene;
    nodes_.clear();
    depth_ = 0;
    prim_ids_.resize(n);
    std::iota(prim_ids_.begin(), prim_ids_.end(), 0u);
    if (n == 0) return;
    // Centroids of the triangles' bounds, in double (exact: half the sum of two floats).
    std::vector<double> centroids(3 * n);
    for (size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a)
            centroids[3 * i + a] =
                0.5 * (double(scene.prim_bounds[i].lower[a]) + double(scene.prim_bounds[i].upper[a]));
    nodes_.reserve(2 * (n / config_.leaf_size + 1));
    build_node(0, uint32_t(n), 0, centroids);
    if (depth_ >= uint32_t(kStackSize))  // cannot happen with median splits; guards the stack
        throw std::logic_error("reference: depth " + std::to_string(depth_) + " exceeds the traversal stack");
}

uint32_t ReferenceAccel::build_node(uint32_t begin, uint32_t end, uint32_t depth,
                                    const std::vector<double>& centroids) {
    const uint32_t index = uint32_t(nodes_.size());
    nodes_.emplace_back();
    depth_ = std::max(depth_, depth);
    Bounds3 bounds;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = begin; i < end; ++i) {
        const uint32_t prim = prim_ids_[i];
        bounds.extend(scene_->prim_bounds[prim]);
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], centroids[3 * prim + a]);
            hi[a] = std::max(hi[a], centroids[3 * prim + a]);
        }
    }
    if (end - begin <= config_.leaf_size) {
        nodes_[index] = {bounds, begin, end - begin};
        return index;
    }
    // Split at the median along the widest extent of the centroids. When all centroids
    // coincide the split still halves the count (ties broken by id), so the depth bound
    // holds for any input.
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    const uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(prim_ids_.begin() + begin, prim_ids_.begin() + mid, prim_ids_.begin() + end,
                     [&](uint32_t x, uint32_t y) {
                         const double cx = centroids[3 * x + axis], cy = centroids[3 * y + axis];
                         return cx < cy || (cx == cy && x < y);
                     });
    build_node(begin, mid, depth + 1, centroids);  // first child: the next node
    const uint32_t second = build_node(mid, end, depth + 1, centroids);
    nodes_[index] = {bounds, second, 0};
    return index;
}

// The tree's statistics as every tree's (tree_tally.h).
BuildStats ReferenceAccel::build_stats() const {
    TreeTally t;
    t.nodes = nodes_.size();
    t.max_depth = depth_;
    t.memory_bytes = nodes_.size() * sizeof(Node) + prim_ids_.size() * sizeof(uint32_t);
    t.root_area = nodes_.empty() ? 0.0 : double(nodes_[0].bounds.area());
    for (const Node& n : nodes_) {
        if (n.count > 0) t.leaf(n.bounds.area(), n.count);
        else t.inner(n.bounds.area());
    }
    return t.stats();
}

template <class C>
void ReferenceAccel::intersect_double(const Ray& ray, ReferenceHit& hit, C& counters) const {
    hit = ReferenceHit{};
    const RayD r(ray);
    if (!r.valid || nodes_.empty()) return;
    struct Entry {
        uint32_t node;
        double tnear;
    };
    Entry stack[kStackSize];
    int top = 0;
    double tnear;
    counters.box();
    if (!intersect_box_conservative(nodes_[0].bounds, r, r.tmin, r.tmax, tnear)) return;
    stack[top++] = {0, tnear};
    // Boxes are searched up to the current best t inclusive, so a hit at exactly that t
    // with a smaller id is still found: the result does not depend on the visit order.
    double best = r.tmax;
    while (top > 0) {
        const Entry e = stack[--top];
        if (e.tnear > enlarge(best)) continue;
        const Node& node = nodes_[e.node];
        counters.node();
        if (node.count > 0) {
            for (uint32_t i = node.index; i < node.index + node.count; ++i) {
                const uint32_t prim = prim_ids_[i];
                counters.prim();
                ReferenceHit h;
                if (!intersect_triangle_double(r, scene_->vertex(prim, 0), scene_->vertex(prim, 1),
                                               scene_->vertex(prim, 2), h))
                    continue;
                if (h.t < hit.t || (h.t == hit.t && prim < hit.prim)) {
                    hit = h;
                    hit.prim = prim;
                    best = h.t;
                }
            }
            continue;
        }
        const uint32_t a = e.node + 1, b = node.index;
        double ta, tb;
        counters.box(2);
        const bool hit_a = intersect_box_conservative(nodes_[a].bounds, r, r.tmin, best, ta);
        const bool hit_b = intersect_box_conservative(nodes_[b].bounds, r, r.tmin, best, tb);
        // Nearer child on top of the stack.
        if (hit_a && hit_b) {
            if (ta <= tb) {
                stack[top++] = {b, tb};
                stack[top++] = {a, ta};
            } else {
                stack[top++] = {a, ta};
                stack[top++] = {b, tb};
            }
        } else if (hit_a) {
            stack[top++] = {a, ta};
        } else if (hit_b) {
            stack[top++] = {b, tb};
        }
    }
}

template <class C>
void ReferenceAccel::intersect(const Ray& ray, Hit& hit, C& counters) const {
    ReferenceHit h;
    intersect_double(ray, h, counters);
    hit = h.found() ? Hit{h.prim, float(h.t), float(h.u), float(h.v)} : Hit{};
}

template <class C>
bool ReferenceAccel::occluded(const Ray& ray, C& counters) const {
    const RayD r(ray);
    if (!r.valid || nodes_.empty()) return false;
    uint32_t stack[kStackSize];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = nodes_[stack[--top]];
        counters.node();
        counters.box();
        double tnear;
        if (!intersect_box_conservative(node.bounds, r, r.tmin, r.tmax, tnear)) continue;
        if (node.count > 0) {
            for (uint32_t i = node.index; i < node.index + node.count; ++i) {
                const uint32_t prim = prim_ids_[i];
                counters.prim();
                ReferenceHit h;
                if (intersect_triangle_double(r, scene_->vertex(prim, 0), scene_->vertex(prim, 1),
                                              scene_->vertex(prim, 2), h))
                    return true;
            }
            continue;
        }
        stack[top++] = node.index;
        stack[top++] = uint32_t(&node - nodes_.data()) + 1;
    }
    return false;
}

template void ReferenceAccel::intersect_double(const Ray&, ReferenceHit&, NoCounters&) const;
template void ReferenceAccel::intersect_double(const Ray&, ReferenceHit&, RayStats&) const;
ACCELBENCH_INSTANTIATE_RAY_QUERIES(ReferenceAccel);

}  // namespace accelbench
