// LBVH speed as ratios against Embree (threads=1), single thread, the form its speed
// goals take: build <= 0.25x Embree's build time, render <= 2x Embree's (ordered
// traversal).
//
//   lbvh_bench [--model=NAME|PATH] [google benchmark flags]
//
// NAME is a registry model (configs/models.yaml; default stanford-bunny), PATH a mesh
// file. "Render" is the renderer with shading off: the primary rays of the model's
// default 640x480 view and one shadow ray per hit.
//
// The machine is shared and noisy, so a ratio of two benchmarks run seconds apart would
// partly measure the load in between. Each benchmark here therefore runs Embree and the
// LBVH alternately within the same iterations, on process CPU time (wall time would also
// count other processes' load), and reports the LBVH's time as the benchmark's time and
// the ratio of the two sums as the counter `vs_embree` (and of the fastest iterations as
// `vs_embree_best`).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstring>
#include <ctime>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "accelbench/camera.h"
#include "accelbench/mesh_io.h"
#include "accelbench/registry.h"
#include "accelbench/renderer.h"
#include "model_registry.h"

using namespace accelbench;

namespace {

using Params = std::map<std::string, std::string>;

struct Model {
    Scene scene;
    Camera camera;
    Light light;
};

Model& model() {
    static Model m;
    return m;
}

void load_model(const std::string& name_or_path) {
    Model& m = model();
    const ModelRegistry registry = ModelRegistry::load_default();
    const ModelEntry* entry = registry.find(name_or_path);
    m.scene = entry ? registry.load_scene(*entry) : load_mesh(name_or_path);
    m.camera = entry && entry->camera ? *entry->camera : Camera::fit(m.scene.bounds, 640.0f / 480.0f);
    m.light = entry && entry->light ? *entry->light : default_light(m.scene.bounds, m.camera);
}

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

// Runs `embree_step` and `lbvh_step` alternately, once each per iteration. Two ratios:
// of the sums (vs_embree) and of the fastest iterations (vs_embree_best), the latter less
// sensitive to load spikes, which slow the LBVH's larger working set more than Embree's.
template <class E, class L>
void interleaved(benchmark::State& state, E&& embree_step, L&& lbvh_step) {
    double embree_total = 0, lbvh_total = 0, embree_best = 1e300, lbvh_best = 1e300;
    for (auto _ : state) {
        const double e = cpu_seconds_of(embree_step);
        const double t = cpu_seconds_of(lbvh_step);
        embree_total += e;
        lbvh_total += t;
        embree_best = std::min(embree_best, e);
        lbvh_best = std::min(lbvh_best, t);
        state.SetIterationTime(t);
    }
    state.counters["embree_ms"] = 1e3 * embree_total / double(state.iterations());
    state.counters["vs_embree"] = lbvh_total / embree_total;
    state.counters["vs_embree_best"] = lbvh_best / embree_best;
}

void report_tree(benchmark::State& state, const Accelerator& lbvh) {
    const BuildStats s = lbvh.build_stats();
    state.counters["nodes"] = double(s.nodes.value_or(0));
    state.counters["sah"] = s.sah_cost.value_or(0);
}

void BM_Build(benchmark::State& state, const Params& params) {
    const Scene& scene = model().scene;
    auto embree = make_accelerator("embree", {{"threads", "1"}});
    auto lbvh = make_accelerator("lbvh", params);
    interleaved(state, [&] { embree->build(scene); }, [&] { lbvh->build(scene); });
    report_tree(state, *lbvh);
}

void BM_Render(benchmark::State& state, const Params& params) {
    const Model& m = model();
    auto embree = make_accelerator("embree", {{"threads", "1"}});
    auto lbvh = make_accelerator("lbvh", params);
    embree->build(m.scene);
    lbvh->build(m.scene);
    TraceRequest request;
    request.settings.shading = false;
    request.light = m.light;
    interleaved(
        state, [&] { benchmark::DoNotOptimize(render(*embree, m.scene, m.camera, request).hits); },
        [&] { benchmark::DoNotOptimize(render(*lbvh, m.scene, m.camera, request).hits); });
    report_tree(state, *lbvh);
}

std::string label(const Params& p) {
    std::string s;
    for (const auto& [k, v] : p) s += (s.empty() ? "" : ",") + k + "=" + v;
    return s.empty() ? "default" : s;
}

void register_benchmarks() {
    for (const Params& p : std::vector<Params>{{}, {{"bits", "21"}}, {{"max_prims", "4"}}})
        benchmark::RegisterBenchmark(("Build/" + label(p)).c_str(), BM_Build, p)
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond);
    for (const Params& p :
         std::vector<Params>{{}, {{"max_prims", "2"}}, {{"max_prims", "4"}}, {{"traversal", "report"}}})
        benchmark::RegisterBenchmark(("Render/" + label(p)).c_str(), BM_Render, p)
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond);
}

}  // namespace

int main(int argc, char** argv) {
    std::string model_name = "stanford-bunny";
    std::vector<char*> rest;
    for (int i = 0; i < argc; ++i) {
        if (std::strncmp(argv[i], "--model=", 8) == 0)
            model_name = argv[i] + 8;
        else
            rest.push_back(argv[i]);
    }
    int rest_argc = int(rest.size());
    benchmark::Initialize(&rest_argc, rest.data());
    load_model(model_name);
    std::printf("model %s: %zu triangles\n", model().scene.name.c_str(), model().scene.triangle_count());
    register_benchmarks();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
