// Camera, renderer and image: the renderer traces exactly the rays the report's setup
// asks for (one primary ray per sample, one shadow ray per hit), whatever is switched on
// around them, and its results do not depend on threads.
#include "accelbench/render/renderer.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <mutex>
#include <optional>
#include <set>

#include "accelbench/accel/registry.h"
#include "accelbench/scene/procedural.h"
#include "agreement.h"

using namespace accelbench;

namespace {

constexpr int kW = 64, kH = 48;
// Dense enough that about half the primary rays of the default view hit.
const std::map<std::string, std::string> kSoup = {{"triangles", "1500"}, {"size", "0.12"}};

struct Fixture {
    ProceduralScene ps;
    std::unique_ptr<Accelerator> accel;
    Camera camera;
};

Fixture prepare(const std::string& kind, const std::map<std::string, std::string>& params,
                const std::string& accel = "brute_force") {
    Fixture f{generate_procedural(kind, params), make_accelerator(accel, {}), {}};
    f.accel->build(f.ps.scene);
    f.camera = f.ps.camera ? *f.ps.camera : Camera::fit(f.ps.scene.bounds, float(kW) / float(kH));
    return f;
}

TraceRequest small_request(CountMode counts) {
    TraceRequest r;
    r.settings.width = kW;
    r.settings.height = kH;
    r.counts = counts;
    return r;
}

bool same(const RayStats& a, const RayStats& b) {
    return a.node_visits == b.node_visits && a.box_tests == b.box_tests && a.prim_tests == b.prim_tests;
}
bool same(const Hit& a, const Hit& b) { return a.prim == b.prim && a.t == b.t && a.u == b.u && a.v == b.v; }

// Everything the counting side of two runs produced is identical.
void expect_same_counts(const TraceOutput& a, const TraceOutput& b) {
    EXPECT_EQ(a.rays, b.rays);
    EXPECT_EQ(a.hits, b.hits);
    EXPECT_EQ(a.shadow_rays, b.shadow_rays);
    EXPECT_EQ(a.shadow_hits, b.shadow_hits);
    EXPECT_TRUE(same(a.primary_stats, b.primary_stats));
    EXPECT_TRUE(same(a.shadow_stats, b.shadow_stats));
    ASSERT_EQ(a.per_pixel.size(), b.per_pixel.size());
    for (size_t i = 0; i < a.per_pixel.size(); ++i) ASSERT_TRUE(same(a.per_pixel[i], b.per_pixel[i])) << "pixel " << i;
    ASSERT_EQ(a.primary_hits.size(), b.primary_hits.size());
    for (size_t i = 0; i < a.primary_hits.size(); ++i)
        ASSERT_TRUE(same(a.primary_hits[i], b.primary_hits[i])) << "ray " << i;
}

}  // namespace

TEST(Camera, FitPutsTheBoundingSphereTangentToTheTopAndBottomEdges) {
    const Bounds3 b{{-1, 2, 3}, {4, 5, 10}};
    const Camera cam = Camera::fit(b, 4.0f / 3.0f);
    const Vec3 c = b.center();
    const float radius = 0.5f * length(b.diagonal());
    EXPECT_NEAR(length(cam.look_at - c), 0.0f, 1e-5f);
    const CameraRays rays(cam, 640, 480);
    // The ray through the middle of the top (and bottom) edge grazes the sphere.
    for (float y : {0.0f, 480.0f}) {
        const Ray r = rays.primary(320.0f, y);
        const Vec3 to_c = c - r.org;
        const float dist = length(to_c - r.dir * dot(to_c, r.dir));
        EXPECT_NEAR(dist, radius, 1e-4f * radius) << "edge y=" << y;
    }
    // The centre ray looks at the centre; the view direction is the one asked for.
    const Ray mid = rays.primary(320.0f, 240.0f);
    EXPECT_NEAR(dot(mid.dir, normalize(c - cam.eye)), 1.0f, 1e-6f);
    EXPECT_NEAR(dot(normalize(c - cam.eye), normalize(Vec3{-0.3f, -0.25f, -1.0f})), 1.0f, 1e-6f);
}

TEST(Camera, PixelZeroZeroIsTheTopLeftCorner) {
    Camera cam;  // at +5 z looking at the origin, y up
    const CameraRays rays(cam, 200, 100);
    const Ray tl = rays.primary(0, 0), br = rays.primary(200, 100);
    EXPECT_LT(tl.dir.x, 0.0f);
    EXPECT_GT(tl.dir.y, 0.0f);
    EXPECT_GT(br.dir.x, 0.0f);
    EXPECT_LT(br.dir.y, 0.0f);
    EXPECT_NEAR(length(tl.dir), 1.0f, 1e-6f);
    // Square pixels: the horizontal half-angle follows from the aspect ratio.
    const Ray right_mid = rays.primary(200, 50);
    EXPECT_NEAR(right_mid.dir.x / -right_mid.dir.z, 2.0f * std::tan(22.5f * 3.14159265f / 180.0f), 1e-5f);
}

TEST(Camera, FitLooksStraightDownWithoutDegenerating) {
    const Camera cam = Camera::fit({{0, 0, 0}, {1, 1, 1}}, 1.0f, {0, -1, 0});
    const CameraRays rays(cam, 8, 8);
    EXPECT_TRUE(is_finite(rays.primary(0, 0).dir));
    EXPECT_TRUE(is_finite(rays.primary(8, 8).dir));
}

TEST(Image, StoresGammaEncodedClampedValues) {
    Image img(2, 1);
    img.set(0, 0, {1.0f, 0.5f, 0.0f});
    img.set(1, 0, {2.0f, -1.0f, std::nanf("")});
    EXPECT_EQ(img.rgb[0], 255);
    EXPECT_EQ(img.rgb[1], 186);  // 255 * 0.5^(1/2.2)
    EXPECT_EQ(img.rgb[2], 0);
    EXPECT_EQ(img.rgb[3], 255);
    EXPECT_EQ(img.rgb[4], 0);
    EXPECT_EQ(img.rgb[5], 0);
}

TEST(Image, WritePngFailureNamesThePath) {
    Image img(4, 4);
    const std::string path = "/nonexistent-accelbench-dir/out.png";
    try {
        img.write_png(path);
        FAIL() << "expected an exception";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
}

TEST(Renderer, WritesANonEmptyPng) {
    Fixture f = prepare("soup", {{"triangles", "500"}});
    TraceRequest r = small_request(CountMode::Off);
    r.albedo = f.ps.albedo;
    TraceOutput out = render(*f.accel, f.ps.scene, f.camera, r);
    ASSERT_TRUE(out.image.has_value());
    const auto path = std::filesystem::temp_directory_path() / "accelbench_renderer_test.png";
    out.image->write_png(path.string());
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::filesystem::remove(path);
    ASSERT_GT(bytes.size(), 8u);
    EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    // Some pixels show geometry, some show sky: the image is not blank.
    size_t distinct = 0;
    for (size_t i = 3; i < out.image->rgb.size(); i += 3) distinct += out.image->rgb[i] != out.image->rgb[0];
    EXPECT_GT(distinct, 0u);
}

TEST(Renderer, ShadingDoesNotChangeWhatIsTraced) {
    Fixture f = prepare("soup", kSoup);
    TraceRequest r = small_request(CountMode::PerPixel);
    r.keep_hits = true;
    TraceOutput shaded = render(*f.accel, f.ps.scene, f.camera, r);
    r.settings.shading = false;
    TraceOutput traced = render(*f.accel, f.ps.scene, f.camera, r);
    EXPECT_TRUE(shaded.image.has_value());
    EXPECT_FALSE(traced.image.has_value());
    EXPECT_GT(shaded.hits, 0u);
    EXPECT_GT(shaded.shadow_hits, 0u);
    EXPECT_GT(shaded.primary_stats.prim_tests, 0u);
    expect_same_counts(shaded, traced);
}

TEST(Renderer, OneShadowRayPerHitOnlyWithALight) {
    Fixture f = prepare("soup", kSoup);
    TraceRequest r = small_request(CountMode::Totals);
    TraceOutput lit = render(*f.accel, f.ps.scene, f.camera, r);
    EXPECT_EQ(lit.rays, uint64_t(kW * kH));
    EXPECT_GT(lit.hits, 0u);
    EXPECT_LT(lit.hits, lit.rays);
    EXPECT_EQ(lit.shadow_rays, lit.hits);
    EXPECT_GT(lit.shadow_stats.prim_tests, 0u);

    r.settings.light = false;
    TraceOutput dark = render(*f.accel, f.ps.scene, f.camera, r);
    EXPECT_EQ(dark.hits, lit.hits);
    EXPECT_EQ(dark.shadow_rays, 0u);
    EXPECT_EQ(dark.shadow_hits, 0u);
    EXPECT_TRUE(same(dark.shadow_stats, RayStats{}));
    EXPECT_TRUE(same(dark.primary_stats, lit.primary_stats));
    ASSERT_TRUE(dark.image.has_value());  // lit by the headlight instead
}

TEST(Renderer, ResultsDoNotDependOnThreads) {
    Fixture f = prepare("forest", {{"triangles", "1000"}});
    for (int spp : {1, 2}) {
        TraceRequest r = small_request(CountMode::PerPixel);
        r.keep_hits = true;
        r.albedo = f.ps.albedo;
        r.light = f.ps.light;
        r.settings.spp = spp;
        TraceOutput one = render(*f.accel, f.ps.scene, f.camera, r);
        r.settings.threads = 2;
        TraceOutput two = render(*f.accel, f.ps.scene, f.camera, r);
        r.settings.threads = 3;
        TraceOutput three = render(*f.accel, f.ps.scene, f.camera, r);
        EXPECT_EQ(one.rays, uint64_t(kW * kH * spp));
        expect_same_counts(one, two);
        expect_same_counts(one, three);
        EXPECT_EQ(one.image->rgb, two.image->rgb) << "spp " << spp;
        EXPECT_EQ(one.image->rgb, three.image->rgb) << "spp " << spp;
    }
}

TEST(Renderer, PerPixelStatsSumToTheTotals) {
    Fixture f = prepare("soup", kSoup);
    TraceRequest r = small_request(CountMode::PerPixel);
    r.settings.spp = 2;
    TraceOutput per = render(*f.accel, f.ps.scene, f.camera, r);
    ASSERT_EQ(per.per_pixel.size(), size_t(kW * kH));
    RayStats sum;
    for (const auto& s : per.per_pixel) sum += s;
    RayStats total = per.primary_stats;
    total += per.shadow_stats;
    EXPECT_TRUE(same(sum, total));
    // Brute force tests every triangle once per primary ray; shadow rays stop at the
    // first occluder, so test at most that many.
    EXPECT_EQ(per.primary_stats.prim_tests, per.rays * 1500u);
    EXPECT_LE(per.shadow_stats.prim_tests, per.shadow_rays * 1500u);
    EXPECT_GT(per.shadow_stats.prim_tests, per.shadow_hits);

    r.counts = CountMode::Totals;
    TraceOutput totals = render(*f.accel, f.ps.scene, f.camera, r);
    EXPECT_TRUE(totals.per_pixel.empty());
    EXPECT_TRUE(same(totals.primary_stats, per.primary_stats));
    EXPECT_TRUE(same(totals.shadow_stats, per.shadow_stats));

    r.counts = CountMode::Off;
    TraceOutput off = render(*f.accel, f.ps.scene, f.camera, r);
    EXPECT_TRUE(same(off.primary_stats, RayStats{}));
    EXPECT_TRUE(same(off.shadow_stats, RayStats{}));
    EXPECT_EQ(off.hits, per.hits);
    EXPECT_EQ(off.shadow_hits, per.shadow_hits);
}

TEST(Renderer, KeptHitsAreInRowMajorPixelOrder) {
    Fixture f = prepare("soup", kSoup);
    TraceRequest r = small_request(CountMode::Off);
    r.keep_hits = true;
    r.settings.shading = false;
    TraceOutput out = render(*f.accel, f.ps.scene, f.camera, r);
    ASSERT_EQ(out.primary_hits.size(), size_t(kW * kH));
    const CameraRays cam(f.camera, kW, kH);
    std::vector<Ray> rays;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) rays.push_back(cam.primary(float(x) + 0.5f, float(y) + 0.5f));
    std::vector<Hit> direct(rays.size());
    f.accel->closest_hits(rays, direct);
    for (size_t i = 0; i < rays.size(); ++i) ASSERT_TRUE(same(out.primary_hits[i], direct[i])) << "ray " << i;

    // With several samples, sample k of pixel (x, y) sits at (y * width + x) * spp + k:
    // each kept hit, projected back through the camera, lands inside its pixel.
    const int spp = 4;
    r.settings.spp = spp;
    TraceOutput four = render(*f.accel, f.ps.scene, f.camera, r);
    ASSERT_EQ(four.primary_hits.size(), size_t(kW * kH * spp));
    const Vec3 fwd = normalize(f.camera.look_at - f.camera.eye);
    const Vec3 right = normalize(cross(fwd, f.camera.up)), up = cross(right, fwd);
    const float half_h = std::tan(0.5f * f.camera.fov_deg * 3.14159265f / 180.0f), half_w = half_h * kW / kH;
    size_t checked = 0, jittered = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const size_t first = (size_t(y) * kW + size_t(x)) * spp;
            for (int k = 0; k < spp; ++k) {
                const Hit& h = four.primary_hits[first + size_t(k)];
                if (!h.found()) continue;
                const Scene& sc = f.ps.scene;
                const Vec3 p =
                    sc.vertex(h.prim, 0) * (1 - h.u - h.v) + sc.vertex(h.prim, 1) * h.u + sc.vertex(h.prim, 2) * h.v;
                const Vec3 d = p - f.camera.eye;
                const float px = (dot(d, right) / dot(d, fwd) / half_w + 1.0f) * 0.5f * kW;
                const float py = (1.0f - dot(d, up) / dot(d, fwd) / half_h) * 0.5f * kH;
                ASSERT_NEAR(px, x + 0.5f, 0.5f + 1e-3f) << "pixel " << x << "," << y << " sample " << k;
                ASSERT_NEAR(py, y + 0.5f, 0.5f + 1e-3f) << "pixel " << x << "," << y << " sample " << k;
                ++checked;
                if (k > 0 && four.primary_hits[first].found() && four.primary_hits[first].t != h.t) ++jittered;
            }
        }
    EXPECT_GT(checked, size_t(kW * kH / 2));
    EXPECT_GT(jittered, 0u);  // samples of a pixel are at different positions
}

TEST(Renderer, TraceRaysMatchesRenderOnTheSameRays) {
    Fixture f = prepare("soup", kSoup);
    TraceRequest r = small_request(CountMode::PerPixel);
    r.keep_hits = true;
    r.settings.shading = false;
    r.light = default_light(f.ps.scene.bounds, f.camera);
    TraceOutput rendered = render(*f.accel, f.ps.scene, f.camera, r);
    const CameraRays cam(f.camera, kW, kH);
    std::vector<Ray> rays;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) rays.push_back(cam.primary(float(x) + 0.5f, float(y) + 0.5f));
    r.settings.threads = 2;
    TraceOutput traced = trace_rays(*f.accel, f.ps.scene, rays, r);
    expect_same_counts(rendered, traced);
    EXPECT_FALSE(traced.image.has_value());
}

TEST(Renderer, RejectsBadSettings) {
    Fixture f = prepare("soup", {{"triangles", "100"}});
    TraceRequest r = small_request(CountMode::Off);
    r.settings.spp = 0;
    EXPECT_THROW(render(*f.accel, f.ps.scene, f.camera, r), std::invalid_argument);
    r = small_request(CountMode::Off);
    r.settings.threads = 0;
    EXPECT_THROW(render(*f.accel, f.ps.scene, f.camera, r), std::invalid_argument);
    r = small_request(CountMode::Off);
    std::vector<Vec3> short_albedo(3);
    r.albedo = short_albedo;
    EXPECT_THROW(render(*f.accel, f.ps.scene, f.camera, r), std::invalid_argument);
}

// Brute force against Embree on every primary ray of an image: the same closest
// primitive, or a tie (a different primitive at the same distance within a few ulps, see
// agreement.h).
TEST(Renderer, BruteForceAndEmbreeAgreeOnEveryPrimaryRay) {
    const std::vector<std::pair<std::string, std::map<std::string, std::string>>> scenes = {
        {"soup", kSoup}, {"forest", {{"triangles", "3000"}}}, {"city", {{"triangles", "3000"}}}};
    for (const auto& [kind, params] : scenes) {
        Fixture bf = prepare(kind, params, "brute_force");
        auto embree = make_accelerator("embree", {{"robust", "true"}});
        embree->build(bf.ps.scene);
        TraceRequest r = small_request(CountMode::Off);
        r.keep_hits = true;
        r.settings.shading = false;
        TraceOutput a = render(*bf.accel, bf.ps.scene, bf.camera, r);
        TraceOutput b = render(*embree, bf.ps.scene, bf.camera, r);
        ASSERT_EQ(a.primary_hits.size(), b.primary_hits.size());
        size_t hits = 0, ties = 0, mismatches = 0;
        for (size_t i = 0; i < a.primary_hits.size(); ++i) {
            const Hit &x = a.primary_hits[i], &y = b.primary_hits[i];
            ASSERT_EQ(x.found(), y.found()) << kind << " ray " << i;
            if (!x.found()) continue;
            ++hits;
            if (x.prim == y.prim) continue;
            if (ulp_distance(x.t, y.t) <= kTieUlps) ++ties;
            else ++mismatches;
        }
        std::printf("[agreement] %s: %zu primary rays, %zu hits, %zu ties, %zu mismatches; shadow hits %llu vs %llu\n",
                    kind.c_str(), a.primary_hits.size(), hits, ties, mismatches, (unsigned long long)a.shadow_hits,
                    (unsigned long long)b.shadow_hits);
        EXPECT_GT(hits, a.primary_hits.size() / 8) << kind;
        EXPECT_EQ(mismatches, 0u) << kind;
        EXPECT_EQ(a.hits, b.hits) << kind;
        EXPECT_EQ(a.shadow_rays, b.shadow_rays) << kind;
    }
}

namespace {

// A real accelerator that also records the floating-point mode of every thread that
// traces through it, closest-hit and any-hit calls alike.
class ModeRecorder final : public Accelerator {
public:
    explicit ModeRecorder(const Accelerator& inner) : inner_(inner) {}
    void build(const Scene&) override {}
    void closest_hits(std::span<const Ray> rays, std::span<Hit> hits, std::span<RayStats> stats) const override {
        record();
        inner_.closest_hits(rays, hits, stats);
    }
    void any_hits(std::span<const Ray> rays, std::span<uint8_t> occluded, std::span<RayStats> stats) const override {
        record();
        inner_.any_hits(rays, occluded, stats);
    }
    BuildStats build_stats() const override { return inner_.build_stats(); }
    std::set<std::optional<FpMode>> modes() const {
        std::lock_guard<std::mutex> lock(mutex_);
        return modes_;
    }

private:
    void record() const {
        std::lock_guard<std::mutex> lock(mutex_);
        modes_.insert(current_fp_mode());
    }
    const Accelerator& inner_;
    mutable std::mutex mutex_;
    mutable std::set<std::optional<FpMode>> modes_;
};

}  // namespace

TEST(FpMode, NamesRoundTripAndUnknownNamesAreRefused) {
    for (std::string_view name : fp_mode_names()) EXPECT_EQ(fp_mode_name(*parse_fp_mode(name)), name);
    EXPECT_EQ(parse_fp_mode("ftz_daz"), FpMode::FtzDaz);
    EXPECT_FALSE(parse_fp_mode("ftz"));
    EXPECT_FALSE(parse_fp_mode("IEEE"));
}

TEST(FpMode, ScopedModeFlushesDenormalsAndRestoresTheCallersMode) {
    ASSERT_EQ(current_fp_mode(), FpMode::Ieee);
    volatile float tiny = 1e-30f, scale = 1e-10f;  // product 1e-40: a float denormal
    EXPECT_GT(tiny * scale, 0.0f);
    {
        const ScopedFpMode mode(FpMode::FtzDaz);
        EXPECT_EQ(current_fp_mode(), FpMode::FtzDaz);
        EXPECT_EQ(tiny * scale, 0.0f);  // FTZ
        volatile float denormal = std::numeric_limits<float>::denorm_min();
        EXPECT_EQ(denormal * 1.0f, 0.0f);  // DAZ
        {
            const ScopedFpMode inner(FpMode::Ieee);
            EXPECT_GT(tiny * scale, 0.0f);
        }
        EXPECT_EQ(current_fp_mode(), FpMode::FtzDaz);
    }
    EXPECT_EQ(current_fp_mode(), FpMode::Ieee);
    EXPECT_GT(tiny * scale, 0.0f);
}

// Every thread that traces runs in the settings' mode, whatever the entry point; the
// caller's own mode is left as it was.
TEST(FpMode, EveryTracingThreadRunsInTheSettingsMode) {
    const Fixture f = prepare("soup", kSoup);
    for (FpMode mode : {FpMode::Ieee, FpMode::FtzDaz}) {
        TraceRequest request = small_request(CountMode::Off);
        request.settings.threads = 3;
        request.settings.fp_mode = mode;
        const ModeRecorder render_side(*f.accel), rays_side(*f.accel), set_side(*f.accel), replay_side(*f.accel);
        render(render_side, f.ps.scene, f.camera, request);
        const std::vector<Ray> rays = camera_rays(f.camera, request.settings);
        trace_rays(rays_side, f.ps.scene, rays, request);
        trace_ray_set(set_side, rays, RayQuery::Any, request);
        render_rays(replay_side, f.ps.scene, f.camera, request);
        const std::set<std::optional<FpMode>> expected = {mode};
        EXPECT_EQ(render_side.modes(), expected) << fp_mode_name(mode);
        EXPECT_EQ(rays_side.modes(), expected) << fp_mode_name(mode);
        EXPECT_EQ(set_side.modes(), expected) << fp_mode_name(mode);
        EXPECT_EQ(replay_side.modes(), expected) << fp_mode_name(mode);
        EXPECT_EQ(current_fp_mode(), FpMode::Ieee);
    }
}

// On an ordinary scene no answer depends on the mode: the same hits, counts and image.
TEST(FpMode, FlushingDenormalsChangesNoAnswerOnAnOrdinaryScene) {
    for (const char* accel : {"bvh", "wbvh", "kdtree", "embree"}) {
        const Fixture f = prepare("soup", kSoup, accel);
        TraceRequest request = small_request(CountMode::PerPixel);
        request.keep_hits = true;
        const TraceOutput ieee = render(*f.accel, f.ps.scene, f.camera, request);
        request.settings.fp_mode = FpMode::FtzDaz;
        const TraceOutput flushed = render(*f.accel, f.ps.scene, f.camera, request);
        expect_same_counts(ieee, flushed);
        ASSERT_TRUE(ieee.image && flushed.image);
        EXPECT_EQ(ieee.image->rgb, flushed.image->rgb) << accel;
    }
}
