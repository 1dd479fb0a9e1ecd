// The standard ray workloads beyond the report's camera rays (Aila and Laine
// 2009, "Understanding the efficiency of ray traversal on GPUs": primary, ambient
// occlusion, diffuse), plus uniformly random rays as the incoherent worst case.
//
// A set is made once per model, before and outside anything timed, from a seed and the
// reference's answers (never from the structure being measured), so every accelerator
// traces exactly the same rays; the set's hash (hash_ray_set) shows that it did. Each ray
// draws from its own random stream (mix_seed of the seed, the set and the ray's index), so
// a set does not depend on the order or the thread it is made in.
//
//   primary  the camera's rays (camera_rays), closest hit: what the report times
//   shadow   from each reference primary hit toward the light, any hit: the report's
//            shadow rays, made exactly as render() makes them (shadow_ray)
//   ao       from each reference primary hit, `ao_samples` cosine-weighted directions
//            over the hemisphere of the geometric normal facing the incoming ray,
//            tmax = ao_distance x the scene's bounding-box diagonal; any hit
//   diffuse  from each reference primary hit a cosine-weighted bounce path of
//            `diffuse_bounces` rays: bounce k+1 starts at bounce k's reference hit
//            (a path ends where the reference misses); closest hit. All bounces are one
//            pooled set, bounce after bounce (bounce_begin says where each starts):
//            a path tracer traces every bounce through the same structure, so the
//            pooled rate is the one it sees, and the CSV keeps one `diffuse` row per
//            combination; later bounces alone would be small sets with noisy times.
//   random   origins uniform in the scene's bounds, directions uniform on the sphere,
//            tmax infinite; closest hit
//
// Secondary rays (ao, diffuse) start at the hit point computed from the barycentrics and
// offset along the normal by offset_ray_origin (Wachter and Binder 2019), with tmin = 0.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "accelbench/accel/accelerator.h"
#include "accelbench/render/renderer.h"
#include "accelbench/scene/scene.h"

namespace accelbench {

// The sets, in the order of their names (ray_set_names()); listed once.
enum class RaySetKind : uint8_t { Primary, Shadow, Ao, Diffuse, Random };

// "primary", "shadow", "ao", "diffuse", "random": the config's and the CSV's spellings.
std::span<const std::string_view> ray_set_names();
std::string_view ray_set_name(RaySetKind kind);
std::optional<RaySetKind> parse_ray_set(std::string_view name);
RayQuery ray_set_query(RaySetKind kind);

struct RaySetParams {
    int ao_samples = 4;             // ao rays per primary hit
    float ao_distance = 0.1f;       // ao tmax as a fraction of the scene's bounding-box diagonal
    int diffuse_bounces = 2;        // depth of each diffuse path
    uint64_t random_rays = 307200;  // size of the random set (640 x 480)
    uint64_t seed = 1;
};

struct GeneratedRaySet {
    RaySetKind kind = RaySetKind::Primary;
    RayQuery query = RayQuery::Closest;
    std::vector<Ray> rays;
    // The reference's answers, one per ray: reference_hits for closest-hit sets,
    // reference_occluded for any-hit sets (the other one is empty).
    std::vector<Hit> reference_hits;
    std::vector<uint8_t> reference_occluded;
    // diffuse: bounce_begin[k] is the index of the first ray of bounce k (one entry per
    // bounce); empty for the other sets.
    std::vector<size_t> bounce_begin;
    uint64_t hash = 0;  // hash_ray_set(rays, query)
};

// Makes the sets `kinds`, in that order. `primary_rays` are the camera's rays
// (camera_rays), `light` the position shadow rays aim at, `reference` the built
// `reference` accelerator on `scene`, through which every set's answers are traced (and
// the primary hits and diffuse bounces the sets start from). Throws
// std::invalid_argument for parameters out of range (samples, bounces < 1, distance <= 0)
// of the sets in `kinds` only.
std::vector<GeneratedRaySet> make_ray_sets(const Accelerator& reference, const Scene& scene,
                                           std::span<const Ray> primary_rays, Vec3 light,
                                           std::span<const RaySetKind> kinds, const RaySetParams& params);

// FNV-1a (64 bit) over the query and every ray's bit pattern (origin, tmin, direction,
// tmax): equal hashes mean, for all practical purposes, identical sets.
uint64_t hash_ray_set(std::span<const Ray> rays, RayQuery query);

// ---- the pieces secondary rays are made of (public for their tests) --------------------

// Wachter and Binder 2019, "A Fast and Robust Method for Avoiding Self-Intersection"
// (Ray Tracing Gems, chapter 6): moves p off the surface along the unit normal n (on the
// side the new ray leaves to) by an integer number of ulps per component, 256 x n's
// component, so the offset grows with the coordinates' magnitude just as their rounding
// error does, whatever the distance from the origin. Near zero, where ulps vanish, a
// fixed offset is added instead. The paper's constants (below 1/32 add n / 65536) are for
// scenes of unit size; here both scale with `scene_size` (the bounding-box diagonal), so
// a scene scaled to 1e-6 is offset like a unit one.
Vec3 offset_ray_origin(Vec3 p, Vec3 n, float scene_size);

// The point of a hit from its barycentrics, p0 + u (p1 - p0) + v (p2 - p0): its error is a
// few ulps of the vertices' coordinates, while org + t dir carries the error of t times
// the ray's length (Wachter and Binder 2019, section 6.2.1).
Vec3 hit_point(const Scene& scene, const Hit& hit);

// The hit triangle's unit geometric normal, turned against `incoming` (toward the side
// the ray came from); nullopt for a triangle without a usable normal (zero area).
std::optional<Vec3> facing_normal(const Scene& scene, const Hit& hit, Vec3 incoming);

// A cosine-weighted direction over the hemisphere of the unit normal n from two uniform
// numbers in [0, 1) (Malley's method: a uniform point on the unit disk lifted onto the
// hemisphere), in the orthonormal basis of Duff et al. 2017 ("Building an Orthonormal
// Basis, Revisited", JCGT 6(1)).
Vec3 cosine_hemisphere(Vec3 n, float u1, float u2);

}  // namespace accelbench
