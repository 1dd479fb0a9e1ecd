// LBVH speed as ratios against Embree (single thread each), the form the speed goals
// take: build <= 0.25x Embree's build time, render <= 2x Embree's (ordered traversal).
//
// The machine these run on is shared and noisy, so a ratio from two separate benchmark
// runs minutes apart would mostly measure the noise. Each benchmark here therefore times
// Embree and the LBVH alternately inside the same iterations and reports the LBVH's time
// as the benchmark's time and the ratio of the two sums as the counter `vs_embree`.
//
//   build/lbvh_bench --benchmark_filter=Build        # build ratios only
//   build/lbvh_bench --benchmark_filter=bunny        # one scene
#include <benchmark/benchmark.h>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "accelbench/camera.h"
#include "accelbench/procedural.h"
#include "accelbench/registry.h"
#include "accelbench/renderer.h"

using namespace accelbench;

namespace {

using Params = std::map<std::string, std::string>;

// Scenes by name, made on first use and kept: loading is not what is measured.
const Scene& bench_scene(const std::string& name) {
    static std::map<std::string, std::unique_ptr<Scene>> cache;
    auto& slot = cache[name];
    if (!slot) {
        if (name == "soup-100k")
            slot = std::make_unique<Scene>(make_procedural("soup", {{"triangles", "100000"}, {"size", "0.02"}}));
        else if (name == "forest")
            slot = std::make_unique<Scene>(make_procedural("forest", {}));
        else
            throw std::runtime_error("lbvh_bench: unknown scene '" + name + "'");
    }
    return *slot;
}

double seconds_of(const std::function<void()>& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::unique_ptr<Accelerator> make_embree() { return make_accelerator("embree", {{"threads", "1"}}); }

void report_tree(benchmark::State& state, const Accelerator& lbvh) {
    const BuildStats s = lbvh.build_stats();
    state.counters["nodes"] = double(s.nodes.value_or(0));
    state.counters["sah"] = s.sah_cost.value_or(0);
}

void BM_Build(benchmark::State& state, const std::string& scene_name, const Params& params) {
    const Scene& scene = bench_scene(scene_name);
    auto embree = make_embree();
    auto lbvh = make_accelerator("lbvh", params);
    double embree_total = 0, lbvh_total = 0;
    for (auto _ : state) {
        embree_total += seconds_of([&] { embree->build(scene); });
        const double t = seconds_of([&] { lbvh->build(scene); });
        lbvh_total += t;
        state.SetIterationTime(t);
    }
    state.counters["embree_ms"] = 1e3 * embree_total / double(state.iterations());
    state.counters["vs_embree"] = lbvh_total / embree_total;
    report_tree(state, *lbvh);
}

// One 640x480 frame of the scene's default view: primary rays and one shadow ray per hit,
// no shading (the same work for both structures, which would only dilute the ratio).
void BM_Render(benchmark::State& state, const std::string& scene_name, const Params& params) {
    const Scene& scene = bench_scene(scene_name);
    auto embree = make_embree();
    auto lbvh = make_accelerator("lbvh", params);
    embree->build(scene);
    lbvh->build(scene);
    TraceRequest request;
    request.settings.shading = false;
    const Camera camera = Camera::fit(scene.bounds, float(request.settings.width) / float(request.settings.height));
    double embree_total = 0, lbvh_total = 0;
    for (auto _ : state) {
        embree_total += seconds_of([&] { render(*embree, scene, camera, request); });
        const double t = seconds_of([&] { render(*lbvh, scene, camera, request); });
        lbvh_total += t;
        state.SetIterationTime(t);
    }
    state.counters["embree_ms"] = 1e3 * embree_total / double(state.iterations());
    state.counters["vs_embree"] = lbvh_total / embree_total;
    report_tree(state, *lbvh);
}

std::string label(const Params& p) {
    std::string s;
    for (const auto& [k, v] : p) s += (s.empty() ? "" : ",") + k + "=" + v;
    return s.empty() ? "default" : s;
}

const bool registered = [] {
    const std::vector<Params> build_configs = {{}, {{"bits", "21"}}, {{"max_prims", "4"}}, {{"threads", "2"}}};
    const std::vector<Params> render_configs = {{}, {{"max_prims", "2"}}, {{"max_prims", "4"}}};
    for (const std::string scene : {"soup-100k", "forest"}) {
        for (const Params& p : build_configs)
            benchmark::RegisterBenchmark(("Build/" + scene + "/" + label(p)).c_str(), BM_Build, scene, p)
                ->UseManualTime()
                ->Unit(benchmark::kMillisecond);
        for (const Params& p : render_configs)
            benchmark::RegisterBenchmark(("Render/" + scene + "/" + label(p)).c_str(), BM_Render, scene, p)
                ->UseManualTime()
                ->Unit(benchmark::kMillisecond);
    }
    return true;
}();

}  // namespace

BENCHMARK_MAIN();
