// What the plugin interface costs: our `bvh` built in, and the same BVH compiled into a
// plugin (harness/bench/plugins/our_bvh_plugin.cpp, loaded like any plugin), traced in the
// same process, interleaved (the order alternates each round), on the rays of a timed
// `accelbench run`: the 640x480 primary rays and one shadow ray per hit, in the renderer's
// batches of one tile. CPU time of each trace; the goal: the plugin within 3% of the
// built-in form, on the bunny and the dragon (docs/benchmarks.md).
//
//   plugin_overhead_bench [--model=NAME]... [--rounds=N]
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "accelbench/accel/registry.h"
#include "accelbench/render/renderer.h"
#include "commands/cli.h"
#include "config/config.h"
#include "models/model_registry.h"

namespace accelbench {
namespace {

double thread_cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// The render's tracing replayed: closest_hits per primary batch, any_hits per shadow batch.
double trace_seconds(const Accelerator& accel, const RenderRays& rays, std::vector<Hit>& hits,
                     std::vector<uint8_t>& occluded) {
    const double t0 = thread_cpu_seconds();
    size_t begin = 0;
    for (size_t end : rays.primary_batch_end) {
        accel.closest_hits(std::span(rays.primary).subspan(begin, end - begin),
                           std::span(hits).subspan(begin, end - begin));
        begin = end;
    }
    begin = 0;
    for (size_t end : rays.shadow_batch_end) {
        accel.any_hits(std::span(rays.shadow).subspan(begin, end - begin),
                       std::span(occluded).subspan(begin, end - begin));
        begin = end;
    }
    return thread_cpu_seconds() - t0;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

// One model: both forms built, their answers compared, then `rounds` interleaved traces.
bool measure(const std::string& name, const ModelRegistry& registry, int rounds) {
    const LoadedModel model = resolve_model(name, registry, RenderSettings{});
    auto builtin = make_accelerator("bvh", {});
    auto plugin = make_accelerator("bvh_plugin", {});
    builtin->build(model.scene);
    plugin->build(model.scene);
    TraceRequest request;  // 640x480, 1 spp, shadow rays, 1 thread
    request.settings.shading = false;
    request.light = model.light;
    const RenderRays rays = render_rays(*builtin, model.scene, model.camera, request);
    std::vector<Hit> hits_a(rays.primary.size()), hits_b(rays.primary.size());
    std::vector<uint8_t> occ_a(rays.shadow.size()), occ_b(rays.shadow.size());
    trace_seconds(*builtin, rays, hits_a, occ_a);
    trace_seconds(*plugin, rays, hits_b, occ_b);
    for (size_t i = 0; i < hits_a.size(); ++i)
        if (hits_a[i].prim != hits_b[i].prim || hits_a[i].t != hits_b[i].t) {
            std::fprintf(stderr, "plugin_overhead_bench: %s: ray %zu answered differently\n", name.c_str(), i);
            return false;
        }
    if (occ_a != occ_b) {
        std::fprintf(stderr, "plugin_overhead_bench: %s: shadow answers differ\n", name.c_str());
        return false;
    }
    std::vector<double> a, b, ratio;
    for (int r = 0; r < rounds; ++r) {
        double ta = 0, tb = 0;
        if (r % 2 == 0) {
            ta = trace_seconds(*builtin, rays, hits_a, occ_a);
            tb = trace_seconds(*plugin, rays, hits_b, occ_b);
        } else {
            tb = trace_seconds(*plugin, rays, hits_b, occ_b);
            ta = trace_seconds(*builtin, rays, hits_a, occ_a);
        }
        a.push_back(ta);
        b.push_back(tb);
        ratio.push_back(tb / ta);
    }
    const double r = median(ratio);
    std::printf("%-18s %9zu %7zu %11.2f %11.2f %8.4f %8.4f  %s\n", name.c_str(),
                rays.primary.size() + rays.shadow.size(), rays.primary_batch_end.size() + rays.shadow_batch_end.size(),
                1e3 * median(a), 1e3 * median(b), median(b) / median(a), r, r <= 1.03 ? "met" : "NOT met");
    return true;
}

}  // namespace
}  // namespace accelbench

int main(int argc, char** argv) {
    using namespace accelbench;
    std::vector<std::string> models;
    int rounds = 30;
    for (int i = 1; i < argc; ++i) {
        if (std::strncmp(argv[i], "--model=", 8) == 0) models.push_back(argv[i] + 8);
        else if (std::strncmp(argv[i], "--rounds=", 9) == 0) rounds = std::max(1, std::atoi(argv[i] + 9));
        else {
            std::fprintf(stderr, "usage: plugin_overhead_bench [--model=NAME]... [--rounds=N]\n");
            return 2;
        }
    }
    if (models.empty()) models = {"stanford-bunny", "stanford-dragon"};
    try {
        load_plugin_file(ACCELBENCH_OVERHEAD_PLUGIN);
        const ModelRegistry registry = ModelRegistry::load_default();
        std::printf("CPU time per trace (median of %d interleaved rounds), built-in bvh vs bvh_plugin\n", rounds);
        std::printf("%-18s %9s %7s %11s %11s %8s %8s  %s\n", "model", "rays", "batches", "builtin_ms", "plugin_ms",
                    "ratio", "med_pair", "goal <= 1.03");
        bool ok = true;
        for (const std::string& m : models) ok &= measure(m, registry, rounds);
        return ok ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "plugin_overhead_bench: %s\n", e.what());
        return 1;
    }
}
