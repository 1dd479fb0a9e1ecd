// Test support: does an accelerator answer the same rays as Embree (the oracle from
// outside)? Used by every structure's tests so they all judge agreement the same way.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "accelbench/accel/registry.h"
#include "accelbench/render/ray_sets.h"
#include "accelbench/scene/scene.h"
#include "accelbench/verify/error_metrics.h"

namespace accelbench::test {

// Deterministic rays that cover a scene: from points on a sphere around the bounds toward
// random points inside them (so most hit), plus rays that start inside the bounds.
inline std::vector<Ray> probe_rays(const Scene& scene, int count, uint64_t seed = 1) {
    uint64_t s = seed * 0x9E3779B97F4A7C15ull + 1;
    auto next = [&s] {  // splitmix64 -> [0, 1)
        uint64_t z = (s += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return float((z ^ (z >> 31)) >> 40) / float(1ull << 24);
    };
    const Vec3 lo = scene.bounds.lower, d = scene.bounds.diagonal(), c = scene.bounds.center();
    const float radius = 0.5f * length(d) * 1.5f + 1e-3f;
    std::vector<Ray> rays;
    rays.reserve(count);
    for (int i = 0; i < count; ++i) {
        Vec3 target = lo + Vec3{next(), next(), next()} * d;
        Vec3 org;
        if (i % 4 == 3) {
            org = lo + Vec3{next(), next(), next()} * d;  // starts inside the bounds
        } else {
            float z = 2 * next() - 1, phi = 6.2831853f * next(), r = std::sqrt(std::max(0.0f, 1 - z * z));
            org = c + Vec3{r * std::cos(phi), r * std::sin(phi), z} * radius;
        }
        Vec3 dir = target - org;
        if (length(dir) == 0) dir = {0, 0, 1};
        rays.push_back({org, 0.0f, normalize(dir), kInfinity});
    }
    return rays;
}

// Shadow rays from each hit point toward a point light above the scene.
inline std::vector<Ray> shadow_rays(const Scene& scene, const std::vector<Ray>& rays, const std::vector<Hit>& hits) {
    const Vec3 light = scene.bounds.center() + Vec3{0.3f, 1.0f, 0.6f} * length(scene.bounds.diagonal());
    const float eps = 1e-4f * length(scene.bounds.diagonal());
    std::vector<Ray> out;
    for (size_t i = 0; i < rays.size(); ++i) {
        if (!hits[i].found()) continue;
        Vec3 p = rays[i].org + rays[i].dir * hits[i].t;
        out.push_back({p, eps, light - p, 1.0f - 1e-4f});
    }
    return out;
}

struct Agreement {
    size_t rays = 0;
    size_t mismatched_hit = 0;   // one found a hit, the other did not
    size_t mismatched_prim = 0;  // different primitive at a clearly different distance
    size_t ties = 0;             // different primitive, same distance within tolerance
    size_t mismatched_occlusion = 0;
};

// Compares closest hits (and any-hit answers for shadow rays) of `accel` against Embree
// on `scene`. A different primitive counts as a tie when the distances agree within
// `ulps` (two triangles meeting where the ray hits them).
inline Agreement compare_with_embree(const Scene& scene, const Accelerator& accel, const std::vector<Ray>& rays,
                                     int64_t ulps = kTieUlps) {
    auto oracle = make_accelerator("embree", {{"robust", "true"}});
    oracle->build(scene);
    Agreement a;
    a.rays = rays.size();
    std::vector<Hit> got(rays.size()), want(rays.size());
    accel.closest_hits(rays, got);
    oracle->closest_hits(rays, want);
    for (size_t i = 0; i < rays.size(); ++i) {
        if (got[i].found() != want[i].found()) {
            ++a.mismatched_hit;
            continue;
        }
        if (!got[i].found() || got[i].prim == want[i].prim) continue;
        if (ulp_distance(got[i].t, want[i].t) <= ulps) ++a.ties;
        else ++a.mismatched_prim;
    }
    std::vector<Ray> shadows = shadow_rays(scene, rays, want);
    std::vector<uint8_t> occ_got(shadows.size()), occ_want(shadows.size());
    accel.any_hits(shadows, occ_got);
    oracle->any_hits(shadows, occ_want);
    for (size_t i = 0; i < shadows.size(); ++i) a.mismatched_occlusion += occ_got[i] != occ_want[i];
    return a;
}

// The assertion every structure test makes: no hit/miss disagreement, no primitive
// disagreement beyond ties, and at most `max_shadow_disagreements` shadow answers
// differing (grazing shadow rays may legitimately differ by rounding between two
// different triangle tests). Prints what it found either way.
inline void expect_agrees_with_embree(const Scene& scene, const Accelerator& accel, const std::vector<Ray>& rays,
                                      const std::string& what, size_t max_hit_disagreements = 0,
                                      size_t max_shadow_disagreements = 0) {
    Agreement a = compare_with_embree(scene, accel, rays);
    std::printf(
        "[agreement] %s: %zu rays, %zu hit/miss mismatches, %zu prim mismatches, %zu ties, %zu shadow mismatches\n",
        what.c_str(), a.rays, a.mismatched_hit, a.mismatched_prim, a.ties, a.mismatched_occlusion);
    EXPECT_LE(a.mismatched_hit, max_hit_disagreements) << what;
    EXPECT_EQ(a.mismatched_prim, 0u) << what;
    EXPECT_LE(a.mismatched_occlusion, max_shadow_disagreements) << what;
}

// The same judgement against a ray set's own reference answers (ray_sets.h), made by the
// double-precision reference when the set was made: closest-hit sets through
// compare_hits (ties allowed), any-hit sets through compare_occlusion. At most
// `max_disagreements` wrong answers (false misses + false hits + wrong primitives).
inline HitErrors expect_agrees_on_ray_set(const GeneratedRaySet& set, const Accelerator& accel, const std::string& what,
                                          uint64_t max_disagreements = 0) {
    TraceRequest request;
    request.keep_hits = true;
    const TraceOutput out = trace_ray_set(accel, set.rays, set.query, request);
    const HitErrors e = set.query == RayQuery::Closest ? compare_hits(out.primary_hits, set.reference_hits)
                                                       : compare_occlusion(out.occluded, set.reference_occluded);
    std::printf(
        "[ray-set agreement] %s %s: %llu rays, %llu false misses, %llu false hits, %llu prim mismatches, "
        "%llu ties\n",
        what.c_str(), std::string(ray_set_name(set.kind)).c_str(), (unsigned long long)e.rays,
        (unsigned long long)e.false_misses, (unsigned long long)e.false_hits, (unsigned long long)e.prim_mismatches,
        (unsigned long long)e.ties);
    EXPECT_EQ(e.nan_results, 0u) << what << " " << ray_set_name(set.kind);
    EXPECT_LE(e.false_misses + e.false_hits + e.prim_mismatches, max_disagreements)
        << what << " " << ray_set_name(set.kind);
    return e;
}

}  // namespace accelbench::test
