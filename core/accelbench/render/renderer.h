// The report's ray tracer setup (section 5, Table 1): one primary ray per pixel sample,
// a point light, Phong shading and one shadow ray per hit toward the light.
//
// It computes only what is asked: no shadow rays without a light, no shading without an
// image (counting runs still trace exactly the same primary and shadow rays), no counters
// unless counting is on. Rays are traced in tiles, one batch call to the accelerator per
// tile, tiles spread over threads (1 thread by default, for measurements).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "accelbench/accel/accelerator.h"
#include "accelbench/base/image.h"
#include "accelbench/render/fp_mode.h"
#include "accelbench/scene/camera.h"
#include "accelbench/scene/light.h"

namespace accelbench {

struct RenderSettings {
    int width = 640;
    int height = 480;
    int spp = 1;          // samples per pixel (stratified jitter, fixed seed, when > 1)
    bool light = true;    // trace shadow rays toward the light
    bool shading = true;  // compute an image (Phong); off: trace only
    int threads = 1;
    // Every tracing thread's (fp_mode.h). FTZ/DAZ, as Embree's documentation asks: measured
    // to cost or gain neither side anything on the bench's models (docs/benchmarks.md).
    FpMode fp_mode = FpMode::FtzDaz;
};

enum class CountMode {
    Off,       // timed runs: no counters at all
    Totals,    // sums over all rays
    PerPixel,  // sums plus one RayStats per pixel (cost images), primary + shadow rays
};

struct TraceOutput {
    uint64_t rays = 0;  // primary (or ray-file, or ray-set) rays
    uint64_t hits = 0;  // of those, how many hit something (any-hit sets: were occluded)
    uint64_t shadow_rays = 0;
    uint64_t shadow_hits = 0;  // shadow rays that found an occluder
    RayStats primary_stats;    // CountMode != Off
    RayStats shadow_stats;
    std::vector<RayStats> per_pixel;  // CountMode::PerPixel, width*height, row-major
    // Only when keep_hits: one per primary ray, in ray order. For render() that is
    // row-major over pixels (top row first) and, within a pixel, sample after sample:
    // index (y * width + x) * spp + s. For trace_rays() it is the order of the input.
    std::vector<Hit> primary_hits;
    // Only when keep_hits and trace_ray_set() traced an any-hit set: one 0/1 per ray.
    std::vector<uint8_t> occluded;
    std::optional<Image> image;  // only when shading
};

struct TraceRequest {
    RenderSettings settings;
    std::optional<Light> light;  // used only when settings.light
    CountMode counts = CountMode::Off;
    bool keep_hits = false;  // keep every primary hit (error measurement)
    // Base colour per triangle (linear RGB) for shading, e.g. a procedural scene's
    // materials; empty: one light grey for everything. Must outlive the call.
    std::span<const Vec3> albedo;
};

// Renders (or only traces) a width x height image through the camera. The light is
// request.light, or default_light(scene.bounds, camera) when absent. With settings.light
// off and shading on, the image is lit by a headlight at the eye (which casts no visible
// shadows, so none are traced). Results do not depend on settings.threads.
TraceOutput render(const Accelerator& accel, const Scene& scene, const Camera& camera, const TraceRequest& request);

// The rays render() traces, made ahead of time so that their tracing can be timed alone
// (harness/bench): the primary rays in render()'s order and batches (one batch per tile),
// and the shadow ray of each primary hit that `accel` finds, batched the same way (empty
// without settings.light). Replaying them — closest_hits over each primary batch, any_hits
// over each shadow batch — is the render's tracing without ray generation or shading.
struct RenderRays {
    std::vector<Ray> primary, shadow;
    std::vector<size_t> primary_batch_end, shadow_batch_end;  // one past each batch's last ray
};
RenderRays render_rays(const Accelerator& accel, const Scene& scene, const Camera& camera, const TraceRequest& request);

// Traces a given ray set (a ray file) instead of camera rays: the same primary / shadow /
// counting logic; no image (settings.shading is ignored, per_pixel is per ray). Without
// request.light the light is the default one of the default view,
// default_light(bounds, Camera::fit(bounds, 4/3)). Shadow rays start at each hit point.
TraceOutput trace_rays(const Accelerator& accel, const Scene& scene, std::span<const Ray> rays,
                       const TraceRequest& request);

// What a ray set asks of each ray: the closest hit, or only whether anything is hit
// (shadow and ambient-occlusion rays).
enum class RayQuery : uint8_t { Closest, Any };

// Traces the rays of one ray set (ray_sets.h) as they are, one query per ray and nothing
// derived from the answers (no shadow rays, no image): rays/hits and primary_stats of the
// output describe these rays; keep_hits keeps primary_hits (Closest) or occluded (Any);
// CountMode::PerPixel gives one RayStats per ray. Only settings.threads and
// settings.fp_mode are read from the settings. Results do not depend on the thread count.
TraceOutput trace_ray_set(const Accelerator& accel, std::span<const Ray> rays, RayQuery query,
                          const TraceRequest& request);

// The camera's rays in the order render() traces and keeps them: pixels row-major (top
// row first), within a pixel sample after sample (the same stratified jitter).
std::vector<Ray> camera_rays(const Camera& camera, const RenderSettings& settings);

// The shadow ray of a hit, as render() makes it: from the hit point org + t dir toward
// the light (which sits at t = 1), the interval stopping shadow_epsilon(scene) (a
// distance) short of both ends.
float shadow_epsilon(const Scene& scene);
Ray shadow_ray(const Ray& primary, const Hit& hit, Vec3 light, float epsilon);

}  // namespace accelbench
