// Build and render speed of the kd-tree against Embree (threads=1), single thread, on one
// model. The kd-tree's speed goals are ratios measured in the same run: render time
// <= 1.5x Embree's; build=nlogn on the 871k-triangle dragon under 4 s. The ratios are
// printed at the end.
//
//   kdtree_bench [--model=NAME|PATH] [google benchmark flags]
//
// NAME is a registry model (configs/models.yaml; default stanford-bunny), PATH a mesh
// file (e.g. dragon_vrip.ply.gz). BM_Trace is the renderer with shading off: the
// primary rays of the model's default 640x480 view plus one shadow ray per hit, the rays
// a timed run traces. BM_Render adds Phong shading, as `accelbench render` times it.
// Times are process CPU time (the machine is shared: wall time would count the other
// processes too).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "accelbench/mesh_io.h"
#include "accelbench/registry.h"
#include "accelbench/renderer.h"
#include "model_registry.h"

using namespace accelbench;

namespace {

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

struct Config {
    std::string label;
    std::string accel;
    std::map<std::string, std::string> params;
    bool render = true;  // false: build only (same tree as another config)
};

const std::vector<Config>& configs() {
    static const std::vector<Config> list = {
        {"embree", "embree", {{"threads", "1"}}},
        {"kdtree", "kdtree", {}},
        {"kdtree_pbrt_build", "kdtree", {{"build", "pbrt"}}, false},
        {"kdtree_leaf4", "kdtree", {{"max_prims", "4"}}},
        {"kdtree_depth100", "kdtree", {{"max_depth", "100"}}},
    };
    return list;
}

void BM_Build(benchmark::State& state, const Config& config) {
    auto accel = make_accelerator(config.accel, config.params);
    for (auto _ : state) accel->build(model().scene);
    const BuildStats st = accel->build_stats();
    if (st.nodes) state.counters["nodes"] = double(*st.nodes);
    state.counters["triangles"] = double(model().scene.triangle_count());
}

void trace(benchmark::State& state, const Config& config, bool shading) {
    auto accel = make_accelerator(config.accel, config.params);
    accel->build(model().scene);
    TraceRequest request;
    request.settings.shading = shading;
    request.light = model().light;
    uint64_t rays = 0;
    for (auto _ : state) {
        const TraceOutput out = render(*accel, model().scene, model().camera, request);
        rays = out.rays + out.shadow_rays;
        benchmark::DoNotOptimize(out.hits);
    }
    state.counters["Mrays/s"] =
        benchmark::Counter(double(rays) * double(state.iterations()) * 1e-6, benchmark::Counter::kIsRate);
}

void BM_Trace(benchmark::State& state, const Config& config) { trace(state, config, false); }
void BM_Render(benchmark::State& state, const Config& config) { trace(state, config, true); }

// Prints each benchmark's CPU time as a ratio to Embree's in the same run.
class RatioReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& r : runs)
            if (r.run_type == Run::RT_Iteration && !r.error_occurred)
                cpu_ms_[r.run_name.function_name] = r.GetAdjustedCPUTime();
    }
    void Finalize() override {
        ConsoleReporter::Finalize();
        std::printf("\nratio to embree (CPU time, %s, %zu triangles):\n", model().scene.name.c_str(),
                    model().scene.triangle_count());
        for (const char* phase : {"BM_Build", "BM_Trace", "BM_Render"}) {
            const auto base = cpu_ms_.find(std::string(phase) + "/embree");
            if (base == cpu_ms_.end()) continue;
            for (const auto& [name, ms] : cpu_ms_)
                if (name.rfind(phase, 0) == 0 && name != base->first)
                    std::printf("  %-32s %8.2f ms  %.2fx\n", name.c_str(), ms, ms / base->second);
        }
    }

private:
    std::map<std::string, double> cpu_ms_;
};

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
    for (const Config& c : configs()) {
        benchmark::RegisterBenchmark(("BM_Build/" + c.label).c_str(), BM_Build, c)
            ->Unit(benchmark::kMillisecond)
            ->MeasureProcessCPUTime();
        if (!c.render) continue;
        benchmark::RegisterBenchmark(("BM_Trace/" + c.label).c_str(), BM_Trace, c)
            ->Unit(benchmark::kMillisecond)
            ->MeasureProcessCPUTime();
        benchmark::RegisterBenchmark(("BM_Render/" + c.label).c_str(), BM_Render, c)
            ->Unit(benchmark::kMillisecond)
            ->MeasureProcessCPUTime();
    }
    RatioReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
}
