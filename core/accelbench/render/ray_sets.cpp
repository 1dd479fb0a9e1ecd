#include "accelbench/render/ray_sets.h"

#include <algorithm>

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "accelbench/base/random.h"

namespace accelbench {

namespace {

constexpr std::array<std::string_view, 5> kNames = {"primary", "shadow", "ao", "diffuse", "random"};

// Wachter and Binder 2019, listing 6-1: offsets of int_scale x n ulps, and below
// `origin` a plain offset of float_scale x n (relative to the scene size here, see
// offset_ray_origin).
constexpr float kIntScale = 256.0f;
constexpr float kOriginFraction = 1.0f / 32.0f;
constexpr float kFloatScaleFraction = 1.0f / 65536.0f;

// Separate random streams per set (and per diffuse bounce): mixed into the seed first,
// so the ao rays of hit i never share a stream with the random set's ray i.
constexpr uint64_t kAoStream = 0xA0;
constexpr uint64_t kDiffuseStream = 0xD1F0;  // + bounce
constexpr uint64_t kRandomStream = 0x7A4D;

SplitMix64 ray_stream(uint64_t seed, uint64_t stream, uint64_t index) {
    return SplitMix64(mix_seed(mix_seed(seed, stream), index));
}

float scene_size(const Scene& scene) {
    const float d = scene.bounds.empty() ? 0.0f : length(scene.bounds.diagonal());
    return d > 0.0f && std::isfinite(d) ? d : 1.0f;
}

std::vector<Hit> reference_closest(const Accelerator& reference, std::span<const Ray> rays) {
    TraceRequest request;
    request.keep_hits = true;
    return trace_ray_set(reference, rays, RayQuery::Closest, request).primary_hits;
}

std::vector<uint8_t> reference_any(const Accelerator& reference, std::span<const Ray> rays) {
    TraceRequest request;
    request.keep_hits = true;
    return trace_ray_set(reference, rays, RayQuery::Any, request).occluded;
}

// A secondary ray leaving a hit in a cosine-weighted direction about the normal facing
// the incoming ray; nullopt when the triangle has no usable normal.
std::optional<Ray> bounce_ray(const Scene& scene, const Ray& incoming, const Hit& hit, SplitMix64& rng, float tmax,
                              float size) {
    const std::optional<Vec3> n = facing_normal(scene, hit, incoming.dir);
    if (!n) return std::nullopt;
    const float u1 = rng.uniform(), u2 = rng.uniform();
    return Ray{offset_ray_origin(hit_point(scene, hit), *n, size), 0.0f, cosine_hemisphere(*n, u1, u2), tmax};
}

struct Path {
    Ray ray;
    Hit hit;
    uint64_t id;  // the primary ray it started from: its random stream
};

}  // namespace

std::span<const std::string_view> ray_set_names() { return kNames; }

std::string_view ray_set_name(RaySetKind kind) { return kNames[size_t(kind)]; }

std::optional<RaySetKind> parse_ray_set(std::string_view name) {
    for (size_t i = 0; i < kNames.size(); ++i)
        if (kNames[i] == name) return RaySetKind(i);
    return std::nullopt;
}

RayQuery ray_set_query(RaySetKind kind) {
    return kind == RaySetKind::Shadow || kind == RaySetKind::Ao ? RayQuery::Any : RayQuery::Closest;
}

uint64_t hash_ray_set(std::span<const Ray> rays, RayQuery query) {
    uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a offset basis
    auto add = [&h](uint32_t word) {
        for (int b = 0; b < 4; ++b) {
            h ^= (word >> (8 * b)) & 0xffu;
            h *= 0x100000001b3ull;  // FNV prime
        }
    };
    add(uint32_t(query));
    for (const Ray& r : rays)
        for (float f : {r.org.x, r.org.y, r.org.z, r.tmin, r.dir.x, r.dir.y, r.dir.z, r.tmax})
            add(std::bit_cast<uint32_t>(f));
    return h;
}

Vec3 offset_ray_origin(Vec3 p, Vec3 n, float size) {
    const float origin = kOriginFraction * size, float_scale = kFloatScaleFraction * size;
    Vec3 out;
    for (int a = 0; a < 3; ++a) {
        // Moving the bit pattern by k moves a float by k ulps; toward larger magnitude
        // when the offset and p have the same sign, so the step is taken along n either way.
        const int32_t k = int32_t(kIntScale * n[a]);
        const int32_t bits = std::bit_cast<int32_t>(p[a]);
        const float moved = std::bit_cast<float>(bits + (p[a] < 0.0f ? -k : k));
        out[a] = std::fabs(p[a]) < origin ? p[a] + float_scale * n[a] : moved;
    }
    return out;
}

Vec3 hit_point(const Scene& scene, const Hit& hit) {
    const Vec3 p0 = scene.vertex(hit.prim, 0), p1 = scene.vertex(hit.prim, 1), p2 = scene.vertex(hit.prim, 2);
    return p0 + (p1 - p0) * hit.u + (p2 - p0) * hit.v;
}

std::optional<Vec3> facing_normal(const Scene& scene, const Hit& hit, Vec3 incoming) {
    const Vec3 p0 = scene.vertex(hit.prim, 0), p1 = scene.vertex(hit.prim, 1), p2 = scene.vertex(hit.prim, 2);
    const Vec3 c = cross(p1 - p0, p2 - p0);
    const float len = length(c);
    if (!(len > 0.0f) || !std::isfinite(len)) return std::nullopt;
    const Vec3 n = c / len;
    return dot(n, incoming) > 0.0f ? -n : n;
}

Vec3 cosine_hemisphere(Vec3 n, float u1, float u2) {
    // Duff et al. 2017, listing 3: b1, b2, n orthonormal for any unit n, no branch on a
    // near-zero component.
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    const Vec3 b1{1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
    const Vec3 b2{b, sign + n.y * n.y * a, -n.y};
    // Malley: r = sqrt(u1) gives a uniform point on the disk; its height over the disk is
    // sqrt(1 - r^2) = sqrt(1 - u1), which makes the density cos(theta) / pi.
    const float r = std::sqrt(u1), phi = 6.28318531f * u2;
    const float z = std::sqrt(std::max(0.0f, 1.0f - u1));
    return normalize(b1 * (r * std::cos(phi)) + b2 * (r * std::sin(phi)) + n * z);
}

std::vector<GeneratedRaySet> make_ray_sets(const Accelerator& reference, const Scene& scene,
                                           std::span<const Ray> primary_rays, Vec3 light,
                                           std::span<const RaySetKind> kinds, const RaySetParams& params) {
    // Only the parameters of the sets asked for: one set's bad parameter is no other's.
    const auto wanted = [&](RaySetKind k) { return std::find(kinds.begin(), kinds.end(), k) != kinds.end(); };
    if (wanted(RaySetKind::Ao) && params.ao_samples < 1)
        throw std::invalid_argument("ray sets: ao samples must be at least 1");
    if (wanted(RaySetKind::Ao) && !(params.ao_distance > 0.0f))
        throw std::invalid_argument("ray sets: ao distance must be positive");
    if (wanted(RaySetKind::Diffuse) && params.diffuse_bounces < 1)
        throw std::invalid_argument("ray sets: diffuse bounces must be at least 1");
    if (wanted(RaySetKind::Random) && params.random_rays < 1)
        throw std::invalid_argument("ray sets: random rays must be at least 1");
    const float size = scene_size(scene);
    // Every set but random starts from the reference's primary hits.
    std::vector<Hit> primary_hits;
    bool need_primary = false;
    for (RaySetKind k : kinds) need_primary |= k != RaySetKind::Random;
    if (need_primary) primary_hits = reference_closest(reference, primary_rays);

    std::vector<GeneratedRaySet> sets;
    for (RaySetKind kind : kinds) {
        GeneratedRaySet set;
        set.kind = kind;
        set.query = ray_set_query(kind);
        switch (kind) {
            case RaySetKind::Primary:
                set.rays.assign(primary_rays.begin(), primary_rays.end());
                set.reference_hits = primary_hits;
                break;
            case RaySetKind::Shadow: {
                const float eps = shadow_epsilon(scene);
                for (size_t i = 0; i < primary_rays.size(); ++i)
                    if (primary_hits[i].found())
                        set.rays.push_back(shadow_ray(primary_rays[i], primary_hits[i], light, eps));
                break;
            }
            case RaySetKind::Ao: {
                const float tmax = params.ao_distance * size;
                const uint64_t samples = uint64_t(params.ao_samples);
                for (size_t i = 0; i < primary_rays.size(); ++i) {
                    if (!primary_hits[i].found()) continue;
                    for (uint64_t s = 0; s < samples; ++s) {
                        SplitMix64 rng = ray_stream(params.seed, kAoStream, uint64_t(i) * samples + s);
                        if (auto r = bounce_ray(scene, primary_rays[i], primary_hits[i], rng, tmax, size))
                            set.rays.push_back(*r);
                    }
                }
                break;
            }
            case RaySetKind::Diffuse: {
                // The paths' current segments: first the primary rays that hit.
                std::vector<Path> paths;
                for (size_t i = 0; i < primary_rays.size(); ++i)
                    if (primary_hits[i].found()) paths.push_back({primary_rays[i], primary_hits[i], uint64_t(i)});
                for (int bounce = 0; bounce < params.diffuse_bounces; ++bounce) {
                    set.bounce_begin.push_back(set.rays.size());
                    std::vector<Path> next;
                    for (const Path& p : paths) {
                        SplitMix64 rng = ray_stream(params.seed, kDiffuseStream + uint64_t(bounce), p.id);
                        if (auto r = bounce_ray(scene, p.ray, p.hit, rng, kInfinity, size))
                            next.push_back({*r, Hit{}, p.id});
                    }
                    std::vector<Ray> rays(next.size());
                    for (size_t j = 0; j < next.size(); ++j) rays[j] = next[j].ray;
                    const std::vector<Hit> hits = reference_closest(reference, rays);
                    set.rays.insert(set.rays.end(), rays.begin(), rays.end());
                    set.reference_hits.insert(set.reference_hits.end(), hits.begin(), hits.end());
                    paths.clear();
                    for (size_t j = 0; j < next.size(); ++j)
                        if (hits[j].found()) paths.push_back({next[j].ray, hits[j], next[j].id});
                }
                break;
            }
            case RaySetKind::Random: {
                const Vec3 lo = scene.bounds.empty() ? Vec3{} : scene.bounds.lower;
                const Vec3 d = scene.bounds.empty() ? Vec3{} : scene.bounds.diagonal();
                set.rays.reserve(params.random_rays);
                for (uint64_t i = 0; i < params.random_rays; ++i) {
                    SplitMix64 rng = ray_stream(params.seed, kRandomStream, i);
                    const Vec3 u{rng.uniform(), rng.uniform(), rng.uniform()};
                    set.rays.push_back({lo + u * d, 0.0f, rng.unit_vector(), kInfinity});
                }
                break;
            }
        }
        // The answers of sets that were not traced while being made.
        if (set.query == RayQuery::Any) set.reference_occluded = reference_any(reference, set.rays);
        else if (set.reference_hits.empty()) set.reference_hits = reference_closest(reference, set.rays);
        set.hash = hash_ray_set(set.rays, set.query);
        sets.push_back(std::move(set));
    }
    return sets;
}

}  // namespace accelbench
