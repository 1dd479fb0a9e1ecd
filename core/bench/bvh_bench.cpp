// Build and render speed of the top-down BVH against Embree (threads=1), on one model,
// single thread: the speed goals of the BVH are ratios to Embree measured in the same
// run (render <= 1.25x Embree for split=sah, <= 2x for median; build <= 0.5x for median,
// <= 1x for sah), printed at the end.
//
//   bvh_bench [--model=NAME|PATH] [google benchmark flags]
//
// NAME is a registry model (configs/models.yaml; default stanford-bunny), PATH a mesh
// file. "Render" is the renderer with shading off: the primary rays of the model's
// default 640x480 view and one shadow ray per hit, exactly the rays a timed run traces.
// Ratios use process CPU time (the machine is shared: wall time would also count the
// other processes' load).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstring>
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
    const float aspect = 640.0f / 480.0f;
    m.camera = entry && entry->camera ? *entry->camera : Camera::fit(m.scene.bounds, aspect);
    m.light = entry && entry->light ? *entry->light : default_light(m.scene.bounds, m.camera);
}

struct Config {
    std::string label;
    std::string accel;
    std::map<std::string, std::string> params;
};

const std::vector<Config>& configs() {
    static const std::vector<Config> list = {
        {"embree", "embree", {{"threads", "1"}}},
        {"bvh_median", "bvh", {}},
        {"bvh_sah", "bvh", {{"split", "sah"}}},
        {"bvh_sah_leaf8", "bvh", {{"split", "sah"}, {"max_prims", "8"}}},
        {"bvh_midpoint", "bvh", {{"split", "midpoint"}}},
    };
    return list;
}

void BM_Build(benchmark::State& state, const Config& config) {
    auto accel = make_accelerator(config.accel, config.params);
    for (auto _ : state) accel->build(model().scene);
    state.counters["triangles"] = double(model().scene.triangle_count());
}

void BM_Render(benchmark::State& state, const Config& config) {
    auto accel = make_accelerator(config.accel, config.params);
    accel->build(model().scene);
    TraceRequest request;
    request.settings.shading = false;
    request.light = model().light;
    uint64_t rays = 0;
    for (auto _ : state) {
        const TraceOutput out = render(*accel, model().scene, model().camera, request);
        rays = out.rays + out.shadow_rays;
        benchmark::DoNotOptimize(out.hits);
    }
    state.counters["Mrays/s"] = benchmark::Counter(double(rays) * double(state.iterations()) * 1e-6,
                                                   benchmark::Counter::kIsRate);
}

// Prints each benchmark's CPU time as a ratio to Embree's in the same run.
class RatioReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& r : runs)
            if (r.run_type == Run::RT_Iteration && !r.error_occurred) cpu_[r.run_name.function_name] = r.GetAdjustedCPUTime();
    }
    void Finalize() override {
        ConsoleReporter::Finalize();
        std::printf("\nratio to embree (CPU time, %s, %zu triangles):\n", model().scene.name.c_str(),
                    model().scene.triangle_count());
        for (const char* phase : {"BM_Build", "BM_Render"}) {
            auto base = cpu_.find(std::string(phase) + "/embree");
            if (base == cpu_.end()) continue;
            for (const auto& [name, t] : cpu_)
                if (name.rfind(phase, 0) == 0 && name != base->first)
                    std::printf("  %-32s %.2fx\n", name.c_str(), t / base->second);
        }
    }

private:
    std::map<std::string, double> cpu_;
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
        benchmark::RegisterBenchmark(("BM_Render/" + c.label).c_str(), BM_Render, c)
            ->Unit(benchmark::kMillisecond)
            ->MeasureProcessCPUTime();
    }
    RatioReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
}
