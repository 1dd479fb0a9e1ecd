// The reference: the ground truth every structure's error columns are measured against.
//
// What makes it a reference rather than one more structure:
// - Everything is computed in double from the float inputs, which convert exactly: the
//   ray (origin, direction, tmin, tmax) and the triangles' vertices.
// - The triangle test decides hit or miss exactly. The three edge functions are signed
//   volumes d . (q_i x q_j) (q = vertex - origin), the watertight test's quantities
//   (Woop, Benthin, Wald 2013) without the shear, so nothing is rounded before the sign
//   is taken. Each is evaluated in double with a forward error bound; when the value is
//   within the bound of zero (an edge or vertex hit, a grazing ray) it is recomputed
//   exactly with floating-point expansions (exact_predicates.h). So two triangles that
//   share an edge always agree on which side a ray passes: no leaks, by construction.
//   Edges and vertices belong to the triangle (all edge functions >= 0, or all <= 0);
//   a triangle whose edge functions are all exactly zero (degenerate, or a ray in its
//   plane) is never hit.
// - Box tests are conservative (Ize 2013, "Robust BVH Ray Traversal -- revised",
//   JCGT 2(2)): the far distance is enlarged by 2 gamma(3) of its magnitude, so rounding
//   can never cull a box the ray really enters.
// - The closest hit is defined without regard to traversal order: the smallest t (as
//   computed in double), then the smallest primitive id among hits with that same t.
//   A hit counts when tmin <= t < tmax, the same half-open interval as triangle.h.
// - Rays that cannot define a line or an interval (!is_valid_ray: a NaN, infinite or
//   huge origin or direction component, a zero direction, a NaN tmin or tmax) hit nothing.
//
// The tree is a plain object-median BVH (its own code, not shared with the structures
// under test, so a bug there cannot hide the same bug here). The median split bounds the
// depth by ceil(log2(N / leaf_size)), which fixes the traversal stack whatever the
// scene, and builds a million triangles in about a second. Node bounds are unions of
// float vertex coordinates and therefore stored in float exactly; all tests are in double.
// Speed is secondary: it is never timed.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "accelbench/accel/accelerator.h"

namespace accelbench {

// A hit with its distance in double (the Hit the Accelerator interface returns carries
// t rounded to the nearest float).
struct ReferenceHit {
    uint32_t prim = kInvalidId;
    double t = std::numeric_limits<double>::infinity();
    double u = 0.0;  // barycentric weight of the triangle's second vertex
    double v = 0.0;  // and of its third

    bool found() const { return prim != kInvalidId; }
};

// The reference triangle test alone (see above). On a hit with ray.tmin <= t < ray.tmax,
// fills t, u, v (not prim) and returns true. Invalid rays and degenerate triangles miss.
bool reference_intersect_triangle(const Ray& ray, Vec3 p0, Vec3 p1, Vec3 p2, ReferenceHit& hit);

class ReferenceAccel final : public AcceleratorBase<ReferenceAccel> {
public:
    // The parameters: each member's initializer is its default; reference.cpp's table
    // declares them.
    struct Config {
        uint32_t leaf_size = 4;  // largest number of triangles in a leaf
        static Config from(const ParamSet& params);
    };

    static AcceleratorInfo info();
    explicit ReferenceAccel(const Config& config) : config_(config) {}

    // Needs a finalized scene (reads prim_bounds). Throws if the scene has more
    // triangles than 32-bit primitive ids can name.
    void build(const Scene& scene) override;
    BuildStats build_stats() const override;

    // The closest hit in double precision.
    template <class C>
    void intersect_double(const Ray& ray, ReferenceHit& hit, C& counters) const;

    template <class C>
    void intersect(const Ray& ray, Hit& hit, C& counters) const;
    template <class C>
    bool occluded(const Ray& ray, C& counters) const;

    // Traversal stack entries: the median split keeps depth <= 32 for any scene of
    // 32-bit primitive ids, and build() checks it.
    static constexpr int kStackSize = 64;

private:
    struct Node {
        Bounds3 bounds;      // exact: unions of float vertex coordinates
        uint32_t index = 0;  // leaf: first slot in prim_ids_; inner: second child
        uint32_t count = 0;  // leaf: number of primitives; inner: 0
    };
    uint32_t build_node(uint32_t begin, uint32_t end, uint32_t depth, const std::vector<double>& centroids);

    Config config_;
    const Scene* scene_ = nullptr;
    std::vector<Node> nodes_;
    std::vector<uint32_t> prim_ids_;
    uint32_t depth_ = 0;
};

}  // namespace accelbench
