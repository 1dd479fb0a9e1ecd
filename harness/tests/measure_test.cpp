// Measuring one combination: what a good run reports, and how a nondeterministic, crashing
// or slow structure is caught (in this process and in a child process).
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <csignal>
#include <cstring>
#include <thread>

#include <sys/wait.h>
#include <unistd.h>

#include "accelbench/accel/baseline/brute_force.h"
#include "accelbench/accel/baseline/embree_accel.h"
#include "harness_test_util.h"
#include "run/measure.h"

namespace accelbench {
namespace {

using namespace testing_util;

// A small closed box of 12 triangles, seen by the default camera.
LoadedModel box_model() {
    LoadedModel m;
    m.scene.name = "box";
    for (int i = 0; i < 8; ++i) m.scene.vertices.push_back({float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)});
    const uint32_t faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
    for (const auto& f : faces) {
        m.scene.triangles.push_back({f[0], f[1], f[2]});
        m.scene.triangles.push_back({f[0], f[2], f[3]});
    }
    m.scene.finalize();
    m.camera = Camera::fit(m.scene.bounds, 4.0f / 3.0f);
    m.light = default_light(m.scene.bounds, m.camera);
    return m;
}

RenderSettings tiny_render() {
    RenderSettings r;
    r.width = 16;
    r.height = 12;
    r.shading = false;
    return r;
}

MeasureSettings quick() {
    MeasureSettings s;
    s.repetitions = 3;
    s.warmup = 1;
    s.show_context = false;
    return s;
}

ParamSet defaults(const AcceleratorInfo& info) { return resolve_params(info.name, info.params, {}); }

// Brute force whose build reports a node count that changes from build to build: the kind
// of bug (uninitialised memory, a data race) the determinism check exists for.
class DriftingBuild final : public Accelerator {
public:
    DriftingBuild() : inner_(BruteForce::Config::from(defaults(BruteForce::info()))) {}
    void build(const Scene& s) override { inner_.build(s); }
    void closest_hits(std::span<const Ray> r, std::span<Hit> h, std::span<RayStats> st) const override {
        inner_.closest_hits(r, h, st);
    }
    void any_hits(std::span<const Ray> r, std::span<uint8_t> o, std::span<RayStats> st) const override {
        inner_.any_hits(r, o, st);
    }
    BuildStats build_stats() const override {
        BuildStats s = inner_.build_stats();
        s.nodes = ++builds_;
        return s;
    }

private:
    BruteForce inner_;
    static inline uint64_t builds_ = 0;
};

AcceleratorInfo test_accel(const char* name, std::function<std::unique_ptr<Accelerator>()> make) {
    return {name, "test structure", {}, [make](const ParamSet&) { return make(); }, fixed_label(name)};
}

TEST(MeasureTest, BruteForceReportsTimesCountsAndJson) {
    const LoadedModel model = box_model();
    const AcceleratorInfo info = BruteForce::info();
    MeasureSettings s = quick();
    s.json = true;
    const Measurement m = measure("box/brute_force", info, defaults(info), model, tiny_render(), s);
    ASSERT_EQ(m.status, "ok") << m.message;
    EXPECT_EQ(m.build_s.size(), 3u);
    EXPECT_EQ(m.render_s.size(), 3u);
    EXPECT_EQ(m.rays, 16u * 12u);
    EXPECT_GT(m.hits, 0u);
    EXPECT_EQ(m.shadow_rays, m.hits);  // light on: one shadow ray per hit
    ASSERT_TRUE(m.counts);
    // Every primary ray tests all 12 triangles; shadow rays stop at the first occluder.
    EXPECT_GE(m.counts->prim_tests, m.rays * 12);
    EXPECT_LE(m.counts->prim_tests, (m.rays + m.shadow_rays) * 12);
    EXPECT_EQ(m.build.nodes, 0u);
    EXPECT_NE(m.json.find("\"name\": \"box/brute_force/render"), std::string::npos) << m.json;
    EXPECT_NE(m.json.find("Mrays/s"), std::string::npos);
}

// The error trace runs after the timed part and is compared with model.reference.
TEST(MeasureTest, ErrorColumnsCompareWithTheModelsReferenceAnswers) {
    LoadedModel model = box_model();
    const AcceleratorInfo info = BruteForce::info();
    add_reference_answers(model, tiny_render());
    ASSERT_EQ(model.reference->hits.size(), 16u * 12u);
    Measurement m = measure("box/brute_force", info, defaults(info), model, tiny_render(), quick());
    ASSERT_EQ(m.status, "ok") << m.message;
    EXPECT_EQ(m.columns.at("false_misses"), "0");
    EXPECT_EQ(m.columns.at("false_hits"), "0");
    EXPECT_EQ(m.columns.at("nan_results"), "0");
    EXPECT_EQ(m.columns.count("image_rmse"), 0u);  // no image in a tracing run
    EXPECT_GT(std::stoull(m.columns.at("peak_rss_bytes")), 0u);

    // Answers that say every ray misses: each of the structure's hits is a false hit.
    auto misses = std::make_shared<ReferenceAnswers>(*model.reference);
    for (Hit& h : misses->hits) h = Hit{};
    model.reference = misses;
    m = measure("box/brute_force", info, defaults(info), model, tiny_render(), quick());
    ASSERT_EQ(m.status, "ok") << m.message;
    EXPECT_EQ(m.columns.at("false_hits"), std::to_string(m.hits));
    EXPECT_EQ(m.columns.at("false_misses"), "0");
    EXPECT_EQ(m.columns.count("t_err_ulp_p50"), 0u);  // no ray where both hit
}

TEST(MeasureTest, EmbreeCountsAreMissingNotZero) {
    const LoadedModel model = box_model();
    const AcceleratorInfo info = EmbreeAccel::info();
    const Measurement m = measure("box/embree", info, defaults(info), model, tiny_render(), quick());
    ASSERT_EQ(m.status, "ok") << m.message;
    EXPECT_FALSE(m.counts);
    EXPECT_FALSE(m.build.nodes);
    EXPECT_EQ(m.rays, 16u * 12u);
}

TEST(MeasureTest, RayFileTracesThoseRays) {
    LoadedModel model = box_model();
    auto rays = std::make_shared<RaySet>();
    rays->rays = {Ray{{0.5f, 0.5f, 5}, 0, {0, 0, -1}, kInfinity}, Ray{{5, 5, 5}, 0, {0, 0, 1}, kInfinity}};
    model.rays = rays;
    const AcceleratorInfo info = BruteForce::info();
    const Measurement m = measure("box-rays/brute_force", info, defaults(info), model, tiny_render(), quick());
    ASSERT_EQ(m.status, "ok") << m.message;
    EXPECT_EQ(m.rays, 2u);
    EXPECT_EQ(m.hits, 1u);
}

// A later process of a combination: its repetitions join the first's with their process
// number, and its deterministic values must equal the first's.
TEST(MeasureTest, ALaterProcessTimesOnlyAndPoolsIntoTheFirst) {
    const LoadedModel model = box_model();
    const AcceleratorInfo info = BruteForce::info();
    MeasureSettings later = quick();
    later.timing_only = true;
    Measurement first = measure("box/brute_force", info, defaults(info), model, tiny_render(), quick());
    const Measurement second = measure("box/brute_force", info, defaults(info), model, tiny_render(), later);
    ASSERT_EQ(first.status, "ok") << first.message;
    ASSERT_EQ(second.status, "ok") << second.message;
    EXPECT_EQ(second.counts->prim_tests, first.counts->prim_tests);  // its counting render ran
    const size_t reps = first.render_s.size();
    pool_process(first, second, 2);
    ASSERT_EQ(first.status, "ok") << first.message;
    EXPECT_EQ(first.render_s.size(), 2 * reps);
    EXPECT_EQ(first.build_s.size(), 2 * reps);
    std::vector<int> expected(reps, 1);
    expected.insert(expected.end(), reps, 2);
    EXPECT_EQ(first.process, expected);
}

TEST(MeasureTest, ProcessesThatDisagreeOrFailFailTheRow) {
    Measurement a;
    a.render_s = a.build_s = {1.0, 1.1};
    a.rays = 10;
    a.build.nodes = 7;
    Measurement b = a;
    b.build.nodes = 9;
    Measurement pooled = a;
    pool_process(pooled, b, 2);
    EXPECT_EQ(pooled.status, "error");
    EXPECT_NE(pooled.message.find("nondeterministic between processes: nodes 7 vs 9"), std::string::npos)
        << pooled.message;

    b = a;
    b.hits = 3;
    pooled = a;
    pool_process(pooled, b, 3);
    EXPECT_NE(pooled.message.find("(process 1 vs process 3)"), std::string::npos) << pooled.message;

    b = a;
    b.status = "timeout";
    b.message = "exceeded the time limit";
    pooled = a;
    pool_process(pooled, b, 2);
    EXPECT_EQ(pooled.status, "timeout");
    EXPECT_EQ(pooled.message, "process 2: exceeded the time limit");
}

TEST(MeasureTest, NondeterministicBuildFailsLoudly) {
    const LoadedModel model = box_model();
    const AcceleratorInfo info = test_accel("drifting", [] { return std::make_unique<DriftingBuild>(); });
    const Measurement m = measure("box/drifting", info, defaults(info), model, tiny_render(), quick());
    EXPECT_EQ(m.status, "error");
    EXPECT_NE(m.message.find("nondeterministic build: nodes"), std::string::npos) << m.message;
    EXPECT_TRUE(m.build_s.empty());  // nothing that could be mistaken for a result
}

TEST(MeasureTest, BuildErrorsBecomeAnErrorStatus) {
    const LoadedModel model = box_model();
    const AcceleratorInfo info = BruteForce::info();
    const ParamSet p = resolve_params(info.name, info.params, {{"max_triangles", "5"}});
    const Measurement m = measure("box/brute_force", info, p, model, tiny_render(), quick());
    EXPECT_EQ(m.status, "error");
    EXPECT_NE(m.message.find("refuses"), std::string::npos) << m.message;
}

TEST(MeasureTest, InProcessTimeLimitIsCheckedBetweenStages) {
    const LoadedModel model = box_model();
    const AcceleratorInfo info = test_accel("slow", [] {
        std::this_thread::sleep_for(std::chrono::milliseconds(60));
        return std::make_unique<BruteForce>(BruteForce::Config::from(defaults(BruteForce::info())));
    });
    MeasureSettings s = quick();
    s.timeout_s = 0.1;
    const Measurement m = measure("box/slow", info, defaults(info), model, tiny_render(), s);
    EXPECT_EQ(m.status, "timeout");
    EXPECT_NE(m.message.find("exceeded the time limit (timeout_s = 0.1 s) before build repetition"), std::string::npos)
        << m.message;
}

// Brute force that writes its tag into a shared log at every build and every traced
// batch: the order in which the stages of interleaved combinations ran.
class LoggingBruteForce final : public Accelerator {
public:
    LoggingBruteForce(char tag, std::string& log)
        : tag_(tag), log_(log), inner_(BruteForce::Config::from(defaults(BruteForce::info()))) {}
    void build(const Scene& s) override {
        log_.push_back(char(std::toupper(tag_)));
        inner_.build(s);
    }
    void closest_hits(std::span<const Ray> r, std::span<Hit> h, std::span<RayStats> st) const override {
        log_.push_back(tag_);
        inner_.closest_hits(r, h, st);
    }
    void any_hits(std::span<const Ray> r, std::span<uint8_t> o, std::span<RayStats> st) const override {
        log_.push_back(tag_);
        inner_.any_hits(r, o, st);
    }
    BuildStats build_stats() const override { return inner_.build_stats(); }

private:
    char tag_;
    std::string& log_;
    BruteForce inner_;
};

// The log's renders, one letter each: every render of the box makes the same number of
// batch calls (`per_render`), so a run of n calls of one tag is n / per_render renders.
std::string renders_in(const std::string& log, size_t per_render) {
    std::string out;
    for (size_t i = 0; i < log.size();) {
        size_t j = i;
        while (j < log.size() && log[j] == log[i]) ++j;
        EXPECT_EQ((j - i) % per_render, 0u) << log;
        out.append((j - i) / per_render, log[i]);
        i = j;
    }
    return out;
}

TEST(MeasureTest, InterleavedCombinationsAlternateRoundByRound) {
    const LoadedModel model = box_model();
    std::string log;
    const AcceleratorInfo a = test_accel("a", [&] { return std::make_unique<LoggingBruteForce>('a', log); });
    const AcceleratorInfo b = test_accel("b", [&] { return std::make_unique<LoggingBruteForce>('b', log); });
    const ParamSet none;
    const std::vector<Measurement> ms =
        measure_jobs({MeasureJob{"box/a", a, none, tiny_render(), quick(), std::nullopt},
                      MeasureJob{"box/b", b, none, tiny_render(), quick(), std::nullopt}},
                     model);
    ASSERT_EQ(ms.size(), 2u);
    // Builds: a's warm-up and round 1, b's; round 2 reversed; round 3 forward.
    std::string builds, traces;
    for (char c : log) (std::isupper(c) ? builds : traces).push_back(c);
    EXPECT_EQ(builds, "AABBBAAB");
    // Renders: round 1 each one's counting render and its first timed one; round 2
    // reversed; round 3 a's timed render and second counting render, then b's.
    const size_t per_render = traces.size() / 10;  // 3 timed + 2 counting renders each
    EXPECT_EQ(renders_in(traces, per_render), "aabbbaaabb");
    const Measurement alone =
        measure("box/brute_force", BruteForce::info(), defaults(BruteForce::info()), model, tiny_render(), quick());
    for (const Measurement& m : ms) {
        ASSERT_EQ(m.status, "ok") << m.message;
        EXPECT_EQ(m.build_s.size(), 3u);
        EXPECT_EQ(m.render_s.size(), 3u);
        // The same answers and counts as measured alone.
        EXPECT_EQ(m.hits, alone.hits);
        EXPECT_EQ(m.shadow_hits, alone.shadow_hits);
        ASSERT_TRUE(m.counts);
        EXPECT_EQ(m.counts->prim_tests, alone.counts->prim_tests);
        // No peak of its own: the process held both structures.
        EXPECT_EQ(m.columns.count("peak_rss_bytes"), 0u);
    }
}

// An interleaved group's console: one summary line per combination and stage, not Google
// Benchmark's row for every repetition (each of its runs is one repetition); all of them
// with --show-repetitions.
TEST(MeasureTest, InterleavedConsoleSummarizesEachCombination) {
    const LoadedModel model = box_model();
    const AcceleratorInfo info = BruteForce::info();
    auto console_of = [&](bool every_repetition, int repetitions = 3) {
        MeasureSettings s = quick();
        s.show_repetitions = every_repetition;
        s.repetitions = repetitions;
        testing::internal::CaptureStdout();
        const std::vector<Measurement> ms =
            measure_jobs({MeasureJob{"box/a", info, defaults(info), tiny_render(), s, std::nullopt},
                          MeasureJob{"box/b", info, defaults(info), tiny_render(), s, std::nullopt}},
                         model);
        const std::string out = testing::internal::GetCapturedStdout();
        for (const Measurement& m : ms) EXPECT_EQ(m.status, "ok") << m.message;
        return out;
    };
    const std::string summary = console_of(false);
    for (const char* name :
         {"box/a/build: median ", "box/a/render: median ", "box/b/build: median ", "box/b/render: median "})
        EXPECT_NE(summary.find(name), std::string::npos) << name << " in:\n" << summary;
    EXPECT_NE(summary.find("of 3 repetitions, interleaved"), std::string::npos) << summary;
    EXPECT_EQ(summary.find("repeats:1"), std::string::npos) << summary;
    const std::string every = console_of(true);
    EXPECT_NE(every.find("box/a/render/iterations:1/repeats:1"), std::string::npos) << every;
    EXPECT_EQ(every.find("box/a/render: median "), std::string::npos) << every;
    // One repetition has no interval of its median (the row's *_ci_lo and *_ci_hi are empty).
    const std::string one = console_of(false, 1);
    EXPECT_NE(one.find("box/b/render: "), std::string::npos) << one;
    EXPECT_NE(one.find(" ms, one repetition, interleaved"), std::string::npos) << one;
    EXPECT_EQ(one.find("["), std::string::npos) << one;
}

TEST(MeasureTest, InterleavedTimeLimitCountsOnlyACombinationsOwnStages) {
    const LoadedModel model = box_model();
    const AcceleratorInfo slow = test_accel("slow", [] {
        std::this_thread::sleep_for(std::chrono::milliseconds(60));
        return std::make_unique<BruteForce>(BruteForce::Config::from(defaults(BruteForce::info())));
    });
    MeasureSettings s = quick();
    s.timeout_s = 0.1;
    const AcceleratorInfo fast = BruteForce::info();
    // Two slow builds pass the limit; the fast combination's own stages do not, however
    // long the slow one took before them.
    const std::vector<Measurement> ms =
        measure_jobs({MeasureJob{"box/slow", slow, defaults(slow), tiny_render(), s, std::nullopt},
                      MeasureJob{"box/fast", fast, defaults(fast), tiny_render(), s, std::nullopt}},
                     model);
    ASSERT_EQ(ms.size(), 2u);
    EXPECT_EQ(ms[0].status, "timeout");
    EXPECT_NE(ms[0].message.find("exceeded the time limit (timeout_s = 0.1 s) before build repetition"),
              std::string::npos)
        << ms[0].message;
    EXPECT_EQ(ms[1].status, "ok") << ms[1].message;
    EXPECT_EQ(ms[1].render_s.size(), 3u);
}

// Bit for bit: floats compared as bytes, so that -0.0, NaN payloads and rounding all count.
template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    // memcmp of an empty vector's (possibly null) data() is undefined even for 0 bytes.
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}
template <class T>
bool same_bits(const T& a, const T& b) {
    return std::memcmp(&a, &b, sizeof(T)) == 0;
}

// A prepared model crosses from the child that prepares it to the run's process as bytes
// (runner.cpp): every field must arrive as it was made, the derived scene arrays included.
TEST(PreparedModelTest, BytesBringBackEveryField) {
    LoadedModel m = box_model();
    for (size_t i = 0; i < m.scene.triangle_count(); ++i) m.albedo.push_back({0.1f * float(i), 0.5f, -0.0f});
    RenderSettings image = tiny_render();
    image.shading = true;
    add_reference_answers(m, image);
    RaySetsSpec sets;
    sets.sets = {RaySetKind::Primary, RaySetKind::Shadow, RaySetKind::Ao, RaySetKind::Diffuse, RaySetKind::Random};
    sets.params.random_rays = 50;
    add_ray_sets(m, image, sets);
    ASSERT_TRUE(m.reference->image);
    ModelSpec spec;
    spec.rays = std::make_shared<RaySet>();

    const std::string bytes = model_wire_bytes(m);
    const LoadedModel back = model_from_wire(bytes, spec);
    EXPECT_EQ(back.scene.name, "box");
    EXPECT_TRUE(same_bits(back.scene.vertices, m.scene.vertices));
    EXPECT_EQ(back.scene.triangles, m.scene.triangles);
    EXPECT_TRUE(same_bits(back.scene.prim_bounds, m.scene.prim_bounds));
    EXPECT_TRUE(same_bits(back.scene.centroids, m.scene.centroids));
    EXPECT_TRUE(same_bits(back.scene.bounds, m.scene.bounds));
    EXPECT_TRUE(same_bits(back.camera, m.camera));
    EXPECT_TRUE(same_bits(back.light, m.light));
    EXPECT_TRUE(same_bits(back.albedo, m.albedo));
    EXPECT_EQ(back.rays, spec.rays);  // the config's ray file, not sent
    ASSERT_TRUE(back.reference);
    EXPECT_EQ(back.reference->seconds, m.reference->seconds);
    EXPECT_TRUE(same_bits(back.reference->hits, m.reference->hits));
    ASSERT_TRUE(back.reference->image);
    EXPECT_EQ(back.reference->image->width, 16);
    EXPECT_EQ(back.reference->image->height, 12);
    EXPECT_EQ(back.reference->image->rgb, m.reference->image->rgb);
    ASSERT_TRUE(back.ray_sets);
    ASSERT_EQ(back.ray_sets->size(), 5u);
    for (size_t i = 0; i < 5; ++i) {
        const GeneratedRaySet &a = (*back.ray_sets)[i], &b = (*m.ray_sets)[i];
        EXPECT_EQ(a.kind, b.kind);
        EXPECT_EQ(a.query, b.query);
        EXPECT_TRUE(same_bits(a.rays, b.rays)) << i;
        EXPECT_TRUE(same_bits(a.reference_hits, b.reference_hits)) << i;
        EXPECT_EQ(a.reference_occluded, b.reference_occluded) << i;
        EXPECT_EQ(a.bounce_begin, b.bounce_begin) << i;
        EXPECT_EQ(a.hash, b.hash) << i;
    }
    EXPECT_FALSE((*back.ray_sets)[3].bounce_begin.empty());  // diffuse: something was compared

    // Without reference or ray sets; and bytes cut short or with more after the model.
    LoadedModel bare = box_model();
    const LoadedModel bare_back = model_from_wire(model_wire_bytes(bare), ModelSpec{});
    EXPECT_FALSE(bare_back.reference);
    EXPECT_FALSE(bare_back.ray_sets);
    EXPECT_FALSE(bare_back.rays);
    for (size_t cut : {size_t(0), size_t(7), bytes.size() / 2, bytes.size() - 1})
        EXPECT_THROW(model_from_wire(bytes.substr(0, cut), spec), std::runtime_error) << cut;
    EXPECT_THROW(model_from_wire(bytes + "x", spec), std::runtime_error);
}

TEST(IsolationTest, ResultCrossesTheProcessBoundary) {
    const LoadedModel model = box_model();
    const AcceleratorInfo info = BruteForce::info();
    const Measurement direct = measure("box/brute_force", info, defaults(info), model, tiny_render(), quick());
    const Measurement m = run_isolated(
        [&](const StageFn& stage) {
            return measure("box/brute_force", info, defaults(info), model, tiny_render(), quick(), stage);
        },
        60);
    ASSERT_EQ(m.status, "ok") << m.message;
    EXPECT_EQ(m.build_s.size(), 3u);
    EXPECT_EQ(m.rays, direct.rays);
    EXPECT_EQ(m.shadow_hits, direct.shadow_hits);
    ASSERT_TRUE(m.counts);
    EXPECT_EQ(m.counts->prim_tests, direct.counts->prim_tests);
    EXPECT_EQ(m.counts->node_visits, direct.counts->node_visits);
}

TEST(IsolationTest, TheWireFormRoundTripsEveryValueExactly) {
    Measurement m;
    m.status = "error";
    m.stage = "render repetition 2 of 3";
    m.message = "line one\nline two \\ with backslash";
    m.build_s = {0.1, 1.0 / 3.0};
    m.render_cpu_s = {std::nextafter(1.0, 2.0)};
    m.instructions = 123456789012ull;
    m.shadow_hits = 5;
    m.build.nodes = 7;
    m.build.sah_cost = 12.5;
    m.build.extra["prim_refs"] = 99;
    m.counts = RayStats{1, 2, 3};
    m.json = "{\n  \"a\": 1\n}";
    m.columns = {{"false_misses", "3"}, {"verdict_counts", "leaks=0 rays=7"}};
    WireWriter w;
    put_measurement(w, m);
    WireReader reader(w.bytes(), "measurement");
    const Measurement r = take_measurement(reader);
    EXPECT_TRUE(reader.at_end());
    EXPECT_EQ(r.columns, m.columns);
    EXPECT_EQ(r.message, m.message);
    EXPECT_EQ(r.build_s, m.build_s);
    EXPECT_EQ(r.build.nodes, 7u);
    EXPECT_FALSE(r.build.leaves);
    EXPECT_EQ(r.build.sah_cost, 12.5);
    EXPECT_EQ(r.build.extra.at("prim_refs"), 99);
    ASSERT_TRUE(r.counts);
    EXPECT_EQ(r.counts->prim_tests, 3u);
    EXPECT_EQ(r.json, m.json);
    EXPECT_EQ(r.status, m.status);
    EXPECT_EQ(r.stage, m.stage);
    EXPECT_EQ(r.render_cpu_s, m.render_cpu_s);  // bit for bit, no text in between
    EXPECT_TRUE(r.render_s.empty());
    EXPECT_EQ(r.instructions, m.instructions);
    EXPECT_EQ(r.shadow_hits, 5u);
    // Cut short anywhere: refused, never read as a shorter measurement.
    for (size_t cut = 0; cut < w.bytes().size(); cut += 7) {
        WireReader part(std::string_view(w.bytes()).substr(0, cut), "measurement");
        EXPECT_THROW(take_measurement(part), std::runtime_error) << cut;
    }
}

TEST(IsolationTest, ACrashIsAnErrorAndTheCallerGoesOn) {
    const Measurement m = run_isolated(
        [](const StageFn& stage) -> Measurement {
            stage("build repetition 1 of 3");
            // The default action, so the child dies from the signal even when a handler is
            // installed: under AddressSanitizer (make test-sanitize) ASan's SEGV handler
            // would otherwise turn the crash into "exit status 1" and the signal number this
            // test checks would never reach the parent.
            std::signal(SIGSEGV, SIG_DFL);
            std::raise(SIGSEGV);
            return {};
        },
        60);
    EXPECT_EQ(m.status, "error");
    EXPECT_NE(m.message.find("signal 11"), std::string::npos) << m.message;
    EXPECT_NE(m.message.find("during build repetition 1 of 3"), std::string::npos) << m.message;
}

// A child stopped by SIGTERM (scancel, kill) or SIGINT is the run being stopped, not a
// failed combination: the caller stops by the same signal and writes no error row for it,
// so that --resume measures the combination again (make test-slurm found such rows).
// The caller here is a forked copy of this test process, so that its death can be seen.
TEST(IsolationTest, AStopRequestStopsTheCallerWithoutARow) {
    for (const int sig : {SIGTERM, SIGINT}) {
        std::fflush(nullptr);
        const pid_t caller = fork();
        ASSERT_GE(caller, 0);
        if (caller == 0) {
            const Measurement m = run_isolated(
                [sig](const StageFn& stage) -> Measurement {
                    stage("build repetition 1 of 1");
                    std::signal(sig, SIG_DFL);
                    std::raise(sig);
                    return {};
                },
                60);
            _exit(m.status == "error" ? 3 : 4);  // returned a row: wrong
        }
        int status = 0;
        ASSERT_EQ(waitpid(caller, &status, 0), caller);
        ASSERT_TRUE(WIFSIGNALED(status)) << "signal " << sig << ": the caller exited with " << WEXITSTATUS(status);
        EXPECT_EQ(WTERMSIG(status), sig);
    }
}

TEST(IsolationTest, ATimeLimitStopsTheChild) {
    const auto t0 = std::chrono::steady_clock::now();
    const Measurement m = run_isolated(
        [](const StageFn& stage) -> Measurement {
            stage("render repetition 2 of 5");
            std::this_thread::sleep_for(std::chrono::seconds(30));
            return {};
        },
        0.3);
    EXPECT_EQ(m.status, "timeout");
    EXPECT_NE(m.message.find("during render repetition 2 of 5"), std::string::npos) << m.message;
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 20.0);
}

}  // namespace
}  // namespace accelbench
