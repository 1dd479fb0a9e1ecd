#include "accelbench/render/renderer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "accelbench/base/random.h"

namespace accelbench {

namespace {

// Rays are traced in square tiles of the image (ray files: in chunks of the same size).
// 16x16 = 256 rays per batch keeps the per-batch buffers in L1/L2 and makes the one
// virtual call per batch negligible, while giving a 640x480 image 1200 tiles to spread
// over threads.
constexpr int kTile = 16;
constexpr size_t kBatchRays = size_t(kTile) * kTile;

// The seed of the stratified jitter pattern (spp > 1). Fixed, so images and counts are
// reproducible; every sample draws from its own stream (mix_seed of pixel and sample), so
// the pattern does not depend on which thread renders which tile.
constexpr uint64_t kSampleSeed = 0x5EED0F5A3D1E5ull;

// Phong coefficients (ambient + diffuse + specular, white light, no distance falloff so
// the exposure does not depend on the scene's units).
constexpr float kAmbient = 0.12f;
constexpr float kDiffuse = 0.78f;
constexpr float kSpecular = 0.25f;
constexpr float kShininess = 32.0f;
constexpr Vec3 kDefaultAlbedo{0.8f, 0.8f, 0.8f};

// Shadow rays start a small distance off the surface so they do not find the triangle
// they start on; relative to the scene so it works whatever the units.
constexpr float kShadowEpsilon = 1e-4f;

// How shadow rays are made for one run.
struct ShadowSetup {
    bool on = false;
    Vec3 light;
    float epsilon = 0.0f;  // in scene units
};

ShadowSetup shadow_setup(const Scene& scene, const TraceRequest& request, const Light& fallback) {
    ShadowSetup s;
    s.on = request.settings.light;
    s.light = request.light ? request.light->position : fallback.position;
    s.epsilon = shadow_epsilon(scene);
    return s;
}

// Counts of one batch; tiles keep their own and the run sums them in tile order.
struct BatchTotals {
    uint64_t rays = 0, hits = 0, shadow_rays = 0, shadow_hits = 0;
    RayStats primary, shadow;

    BatchTotals& operator+=(const BatchTotals& o) {
        rays += o.rays;
        hits += o.hits;
        shadow_rays += o.shadow_rays;
        shadow_hits += o.shadow_hits;
        primary += o.primary;
        shadow += o.shadow;
        return *this;
    }
};

// One thread's buffers, reused batch after batch.
struct Scratch {
    std::vector<Ray> rays;  // render(): the tile's camera rays
    std::vector<Hit> hits;
    std::vector<RayStats> primary_stats;
    std::vector<Ray> shadow_rays;
    std::vector<uint32_t> shadow_of;  // shadow ray j belongs to primary ray shadow_of[j]
    std::vector<uint8_t> occluded;
    std::vector<RayStats> shadow_stats;
    std::vector<uint8_t> lit;    // per primary ray: its shadow ray reached the light
    std::vector<RayStats> cost;  // per primary ray: primary + shadow stats (PerPixel)
};

// Traces one batch: one closest_hits call for the rays, then one any_hits call for the
// shadow rays of those that hit. Afterwards s.hits, s.lit and (PerPixel) s.cost hold one
// entry per ray.
BatchTotals trace_batch(const Accelerator& accel, std::span<const Ray> rays, const ShadowSetup& shadow,
                        CountMode counts, Scratch& s) {
    const size_t n = rays.size();
    const bool counting = counts != CountMode::Off;
    BatchTotals t;
    t.rays = n;

    s.hits.resize(n);
    if (counting) s.primary_stats.assign(n, RayStats{});
    accel.closest_hits(rays, s.hits, counting ? std::span<RayStats>(s.primary_stats) : std::span<RayStats>{});

    s.lit.assign(n, 1);
    s.shadow_rays.clear();
    s.shadow_of.clear();
    for (size_t i = 0; i < n; ++i) {
        if (!s.hits[i].found()) continue;
        ++t.hits;
        if (!shadow.on) continue;
        s.shadow_rays.push_back(shadow_ray(rays[i], s.hits[i], shadow.light, shadow.epsilon));
        s.shadow_of.push_back(uint32_t(i));
    }
    const size_t m = s.shadow_rays.size();
    t.shadow_rays = m;
    if (m > 0) {
        s.occluded.resize(m);
        if (counting) s.shadow_stats.assign(m, RayStats{});
        accel.any_hits(s.shadow_rays, s.occluded,
                       counting ? std::span<RayStats>(s.shadow_stats) : std::span<RayStats>{});
        for (size_t j = 0; j < m; ++j) {
            t.shadow_hits += s.occluded[j];
            if (s.occluded[j]) s.lit[s.shadow_of[j]] = 0;
        }
    }

    if (counting) {
        for (size_t i = 0; i < n; ++i) t.primary += s.primary_stats[i];
        for (size_t j = 0; j < m; ++j) t.shadow += s.shadow_stats[j];
    }
    if (counts == CountMode::PerPixel) {
        s.cost.assign(s.primary_stats.begin(), s.primary_stats.end());
        for (size_t j = 0; j < m; ++j) s.cost[s.shadow_of[j]] += s.shadow_stats[j];
    }
    return t;
}

// Runs work(batch, scratch) for every batch in [0, count) on `threads` threads (the calling
// thread is one of them), each in the floating-point mode `mode` (the calling thread's is
// restored afterwards). Batches are handed out by an atomic counter, so a slow tile does
// not hold up the others. The first exception stops the remaining batches and is
// rethrown here.
template <class Work>
void for_each_batch(size_t count, int threads, FpMode mode, Work&& work) {
    std::atomic<size_t> next{0};
    std::exception_ptr error;
    std::mutex error_mutex;
    auto worker = [&] {
        const ScopedFpMode fp_mode(mode);
        Scratch scratch;
        try {
            for (size_t b; (b = next.fetch_add(1)) < count;) work(b, scratch);
        } catch (...) {
            std::lock_guard<std::mutex> lock(error_mutex);
            if (!error) error = std::current_exception();
            next.store(count);
        }
    };
    const size_t extra = size_t(std::max(1, threads)) - 1;
    std::vector<std::thread> pool;
    pool.reserve(extra);
    for (size_t i = 0; i < std::min(extra, count); ++i) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
    if (error) std::rethrow_exception(error);
}

// Sums per-batch totals in batch order into the output (the order makes no difference
// to integer sums, but keeps the result independent of scheduling by construction).
void add_totals(const std::vector<BatchTotals>& batches, TraceOutput& out) {
    BatchTotals sum;
    for (const auto& b : batches) sum += b;
    out.rays = sum.rays;
    out.hits = sum.hits;
    out.shadow_rays = sum.shadow_rays;
    out.shadow_hits = sum.shadow_hits;
    out.primary_stats = sum.primary;
    out.shadow_stats = sum.shadow;
}

void check_settings(const RenderSettings& s, bool image) {
    if (image && (s.width <= 0 || s.height <= 0))
        throw std::invalid_argument("render: width and height must be positive");
    if (image && s.spp <= 0) throw std::invalid_argument("render: spp must be at least 1");
    if (s.threads <= 0) throw std::invalid_argument("render: threads must be at least 1");
}

// Background seen by rays that miss: a sky gradient, pale haze at and below the horizon,
// deeper blue overhead (relative to the camera's up).
Vec3 sky(Vec3 dir, Vec3 up) {
    const float k = std::sqrt(std::clamp(dot(normalize(dir), up), 0.0f, 1.0f));
    const Vec3 horizon{0.80f, 0.86f, 0.92f}, zenith{0.30f, 0.48f, 0.78f};
    return horizon + (zenith - horizon) * k;
}

// Phong at a hit: ambient + diffuse + specular, with the geometric normal turned toward
// the viewer (meshes are not consistently oriented, and the report shades both sides).
// `lit` is false when the shadow ray found an occluder: then only ambient remains.
Vec3 shade(const Scene& scene, std::span<const Vec3> albedo, const Ray& ray, const Hit& hit, Vec3 light, bool lit) {
    const Vec3 p0 = scene.vertex(hit.prim, 0), p1 = scene.vertex(hit.prim, 1), p2 = scene.vertex(hit.prim, 2);
    const Vec3 view = normalize(-ray.dir);
    Vec3 n = cross(p1 - p0, p2 - p0);
    const float len = length(n);
    n = len > 0.0f ? n / len : view;
    if (dot(n, view) < 0.0f) n = -n;

    const Vec3 base = albedo.empty() ? kDefaultAlbedo : albedo[hit.prim];
    Vec3 c = base * kAmbient;
    if (!lit) return c;
    const Vec3 p = ray.org + ray.dir * hit.t;
    const Vec3 to_light = light - p;
    const float dist = length(to_light);
    if (!(dist > 0.0f)) return c;
    const Vec3 l = to_light / dist;
    const float ndl = dot(n, l);
    if (ndl <= 0.0f) return c;  // the light is behind the face the viewer sees
    c += base * (kDiffuse * ndl);
    const Vec3 r = n * (2.0f * ndl) - l;  // mirror direction of the light
    const float rv = std::max(0.0f, dot(r, view));
    c += Vec3{1, 1, 1} * (kSpecular * std::pow(rv, kShininess));
    return c;
}

// The sample position inside a pixel: the centre for one sample; otherwise a jittered
// point in cell s of a gx x gy grid covering the pixel (stratified sampling).
void sample_offset(int s, int spp, uint64_t pixel, float& dx, float& dy) {
    if (spp == 1) {
        dx = dy = 0.5f;
        return;
    }
    const int gx = int(std::ceil(std::sqrt(float(spp))));
    const int gy = (spp + gx - 1) / gx;
    SplitMix64 rng(mix_seed(kSampleSeed, pixel * uint64_t(spp) + uint64_t(s)));
    dx = (float(s % gx) + rng.uniform()) / float(gx);
    dy = (float(s / gx) + rng.uniform()) / float(gy);
}

// Sample k of pixel (x, y).
Ray pixel_ray(const CameraRays& cam, const RenderSettings& rs, int x, int y, int k) {
    float dx, dy;
    sample_offset(k, rs.spp, uint64_t(y) * uint64_t(rs.width) + uint64_t(x), dx, dy);
    return cam.primary(float(x) + dx, float(y) + dy);
}

// The primary rays of one tile, in the order render() traces them: rows of the tile top to
// bottom, pixels left to right, a pixel's samples in turn.
void tile_primary_rays(const CameraRays& cam, const RenderSettings& rs, size_t tile, std::vector<Ray>& rays) {
    const int tiles_x = (rs.width + kTile - 1) / kTile;
    const int x0 = int(tile % size_t(tiles_x)) * kTile, y0 = int(tile / size_t(tiles_x)) * kTile;
    const int x1 = std::min(x0 + kTile, rs.width), y1 = std::min(y0 + kTile, rs.height);
    rays.clear();
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            for (int k = 0; k < rs.spp; ++k) rays.push_back(pixel_ray(cam, rs, x, y, k));
}

size_t tile_count(const RenderSettings& rs) {
    return size_t((rs.width + kTile - 1) / kTile) * size_t((rs.height + kTile - 1) / kTile);
}

}  // namespace

RenderRays render_rays(const Accelerator& accel, const Scene& scene, const Camera& camera,
                       const TraceRequest& request) {
    const RenderSettings& rs = request.settings;
    check_settings(rs, true);
    const CameraRays cam(camera, rs.width, rs.height);
    const ShadowSetup shadow = shadow_setup(scene, request, default_light(scene.bounds, camera));
    const ScopedFpMode fp_mode(rs.fp_mode);
    RenderRays out;
    std::vector<Ray> rays;
    std::vector<Hit> hits;
    for (size_t tile = 0; tile < tile_count(rs); ++tile) {
        tile_primary_rays(cam, rs, tile, rays);
        hits.resize(rays.size());
        accel.closest_hits(rays, hits);
        out.primary.insert(out.primary.end(), rays.begin(), rays.end());
        out.primary_batch_end.push_back(out.primary.size());
        if (!shadow.on) continue;
        for (size_t i = 0; i < rays.size(); ++i)
            if (hits[i].found()) out.shadow.push_back(shadow_ray(rays[i], hits[i], shadow.light, shadow.epsilon));
        out.shadow_batch_end.push_back(out.shadow.size());
    }
    return out;
}

float shadow_epsilon(const Scene& scene) {
    const float size = scene.bounds.empty() ? 0.0f : length(scene.bounds.diagonal());
    return kShadowEpsilon * (size > 0.0f ? size : 1.0f);
}

Ray shadow_ray(const Ray& primary, const Hit& hit, Vec3 light, float epsilon) {
    const Vec3 p = primary.org + primary.dir * hit.t;
    const Vec3 d = light - p;
    const float dist = length(d);
    const float eps_t = dist > 0.0f ? epsilon / dist : 0.0f;
    return {p, eps_t, d, 1.0f - eps_t};
}

std::vector<Ray> camera_rays(const Camera& camera, const RenderSettings& settings) {
    check_settings(settings, true);
    const CameraRays cam(camera, settings.width, settings.height);
    std::vector<Ray> rays;
    rays.reserve(size_t(settings.width) * size_t(settings.height) * size_t(settings.spp));
    for (int y = 0; y < settings.height; ++y)
        for (int x = 0; x < settings.width; ++x)
            for (int k = 0; k < settings.spp; ++k) rays.push_back(pixel_ray(cam, settings, x, y, k));
    return rays;
}

TraceOutput render(const Accelerator& accel, const Scene& scene, const Camera& camera, const TraceRequest& request) {
    const RenderSettings& rs = request.settings;
    check_settings(rs, true);
    if (!request.albedo.empty() && request.albedo.size() != scene.triangle_count())
        throw std::invalid_argument("render: albedo must have one colour per triangle");

    const CameraRays cam(camera, rs.width, rs.height);
    const ShadowSetup shadow = shadow_setup(scene, request, default_light(scene.bounds, camera));
    // Without a light an image is still lit, by a headlight at the eye.
    const Vec3 shading_light = shadow.on ? shadow.light : camera.eye;
    const Vec3 sky_up = normalize(camera.up);

    const int spp = rs.spp;
    const int tiles_x = (rs.width + kTile - 1) / kTile;
    const size_t tiles = tile_count(rs);
    const size_t pixels = size_t(rs.width) * size_t(rs.height);

    TraceOutput out;
    if (request.counts == CountMode::PerPixel) out.per_pixel.assign(pixels, RayStats{});
    if (request.keep_hits) out.primary_hits.resize(pixels * size_t(spp));
    if (rs.shading) out.image.emplace(rs.width, rs.height);
    std::vector<BatchTotals> totals(tiles);

    // Tiles write disjoint pixels of the shared outputs, so they need no locking.
    for_each_batch(tiles, rs.threads, rs.fp_mode, [&](size_t tile, Scratch& s) {
        const int x0 = int(tile % size_t(tiles_x)) * kTile, y0 = int(tile / size_t(tiles_x)) * kTile;
        const int x1 = std::min(x0 + kTile, rs.width), y1 = std::min(y0 + kTile, rs.height);
        tile_primary_rays(cam, rs, tile, s.rays);
        totals[tile] = trace_batch(accel, s.rays, shadow, request.counts, s);

        size_t i = 0;  // ray index within the tile, in the order the rays were made
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const size_t pixel = size_t(y) * size_t(rs.width) + size_t(x);
                Vec3 colour;
                for (int k = 0; k < spp; ++k, ++i) {
                    if (request.keep_hits) out.primary_hits[pixel * size_t(spp) + size_t(k)] = s.hits[i];
                    if (request.counts == CountMode::PerPixel) out.per_pixel[pixel] += s.cost[i];
                    if (rs.shading)
                        colour += s.hits[i].found()
                            ? shade(scene, request.albedo, s.rays[i], s.hits[i], shading_light, s.lit[i] != 0)
                            : sky(s.rays[i].dir, sky_up);
                }
                if (rs.shading) out.image->set(x, y, colour / float(spp));
            }
    });
    add_totals(totals, out);
    return out;
}

TraceOutput trace_rays(const Accelerator& accel, const Scene& scene, std::span<const Ray> rays,
                       const TraceRequest& request) {
    check_settings(request.settings, false);
    const ShadowSetup shadow = shadow_setup(
        scene, request,
        request.light ? *request.light : default_light(scene.bounds, Camera::fit(scene.bounds, 4.0f / 3.0f)));

    const size_t batches = (rays.size() + kBatchRays - 1) / kBatchRays;
    TraceOutput out;
    if (request.counts == CountMode::PerPixel) out.per_pixel.resize(rays.size());
    if (request.keep_hits) out.primary_hits.resize(rays.size());
    std::vector<BatchTotals> totals(batches);

    for_each_batch(batches, request.settings.threads, request.settings.fp_mode, [&](size_t b, Scratch& s) {
        const size_t first = b * kBatchRays;
        const std::span<const Ray> batch = rays.subspan(first, std::min(kBatchRays, rays.size() - first));
        totals[b] = trace_batch(accel, batch, shadow, request.counts, s);
        for (size_t i = 0; i < batch.size(); ++i) {
            if (request.keep_hits) out.primary_hits[first + i] = s.hits[i];
            if (request.counts == CountMode::PerPixel) out.per_pixel[first + i] = s.cost[i];
        }
    });
    add_totals(totals, out);
    return out;
}

TraceOutput trace_ray_set(const Accelerator& accel, std::span<const Ray> rays, RayQuery query,
                          const TraceRequest& request) {
    check_settings(request.settings, false);
    const size_t batches = (rays.size() + kBatchRays - 1) / kBatchRays;
    const bool counting = request.counts != CountMode::Off;
    TraceOutput out;
    if (request.counts == CountMode::PerPixel) out.per_pixel.resize(rays.size());
    if (request.keep_hits && query == RayQuery::Closest) out.primary_hits.resize(rays.size());
    if (request.keep_hits && query == RayQuery::Any) out.occluded.resize(rays.size());
    std::vector<BatchTotals> totals(batches);

    // Batches write disjoint ranges of the outputs and keep their own totals, summed in
    // batch order below: nothing depends on which thread traced which batch.
    for_each_batch(batches, request.settings.threads, request.settings.fp_mode, [&](size_t b, Scratch& s) {
        const size_t first = b * kBatchRays;
        const std::span<const Ray> batch = rays.subspan(first, std::min(kBatchRays, rays.size() - first));
        const size_t n = batch.size();
        if (counting) s.primary_stats.assign(n, RayStats{});
        const std::span<RayStats> stats = counting ? std::span<RayStats>(s.primary_stats) : std::span<RayStats>{};
        BatchTotals& t = totals[b];
        t.rays = n;
        if (query == RayQuery::Closest) {
            s.hits.resize(n);
            accel.closest_hits(batch, s.hits, stats);
            for (size_t i = 0; i < n; ++i) t.hits += s.hits[i].found() ? 1 : 0;
            if (request.keep_hits) std::copy(s.hits.begin(), s.hits.end(), out.primary_hits.begin() + ptrdiff_t(first));
        } else {
            s.occluded.resize(n);
            accel.any_hits(batch, s.occluded, stats);
            for (size_t i = 0; i < n; ++i) t.hits += s.occluded[i];
            if (request.keep_hits)
                std::copy(s.occluded.begin(), s.occluded.end(), out.occluded.begin() + ptrdiff_t(first));
        }
        if (!counting) return;
        for (size_t i = 0; i < n; ++i) t.primary += s.primary_stats[i];
        if (request.counts == CountMode::PerPixel)
            std::copy(s.primary_stats.begin(), s.primary_stats.end(), out.per_pixel.begin() + ptrdiff_t(first));
    });
    add_totals(totals, out);
    return out;
}

}  // namespace accelbench
