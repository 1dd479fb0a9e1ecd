// Our own BVH (accel/bvh/bvh.h, at its defaults) behind the plugin interface, compiled into
// a shared library of its own: plugin_overhead_bench traces it beside the built-in `bvh`
// in the same process, so the difference is what the interface costs (the loader's
// wrapper, the C call per batch, this adapter) and nothing else.
#include <accelbench/plugin/accelbench_plugin.h>

#include <cstdio>
#include <memory>

#include "accelbench/accel/bvh/bvh.h"

namespace {

using namespace accelbench;

struct Structure {
    Scene scene;  // the plugin's copy: Bvh keeps a reference to the scene it was built over
    std::unique_ptr<Accelerator> bvh;
};

Structure& self(accelbench_structure* s) { return *reinterpret_cast<Structure*>(s); }
const Structure& self(const accelbench_structure* s) { return *reinterpret_cast<const Structure*>(s); }

accelbench_structure* create(const accelbench_param_value*, uint32_t, char* error, size_t error_size) {
    try {
        auto s = std::make_unique<Structure>();
        const AcceleratorInfo info = Bvh::info();
        s->bvh = info.create(resolve_params(info.name, info.params, {}));
        return reinterpret_cast<accelbench_structure*>(s.release());
    } catch (const std::exception& e) {
        std::snprintf(error, error_size, "%s", e.what());
        return nullptr;
    }
}

int build(accelbench_structure* handle, const accelbench_scene* scene, char* error, size_t error_size) {
    try {
        Structure& s = self(handle);
        const auto* v = reinterpret_cast<const Vec3*>(scene->vertices);
        const auto* t = reinterpret_cast<const std::array<uint32_t, 3>*>(scene->indices);
        s.scene.vertices.assign(v, v + scene->vertex_count);
        s.scene.triangles.assign(t, t + scene->triangle_count);
        s.scene.finalize();
        s.bvh->build(s.scene);
        return 0;
    } catch (const std::exception& e) {
        std::snprintf(error, error_size, "%s", e.what());
        return 1;
    }
}

std::span<RayStats> stats(accelbench_ray_counters* counters, uint64_t count) {
    return counters ? std::span(reinterpret_cast<RayStats*>(counters), count) : std::span<RayStats>();
}

void closest_hits(const accelbench_structure* handle, const accelbench_ray* rays, accelbench_hit* hits, uint64_t count,
                  accelbench_ray_counters* counters) {
    self(handle).bvh->closest_hits(std::span(reinterpret_cast<const Ray*>(rays), count),
                                   std::span(reinterpret_cast<Hit*>(hits), count), stats(counters, count));
}

void any_hits(const accelbench_structure* handle, const accelbench_ray* rays, uint8_t* occluded, uint64_t count,
              accelbench_ray_counters* counters) {
    self(handle).bvh->any_hits(std::span(reinterpret_cast<const Ray*>(rays), count), std::span(occluded, count),
                               stats(counters, count));
}

void build_stats(const accelbench_structure* handle, accelbench_build_stats* out) {
    const BuildStats b = self(handle).bvh->build_stats();
    *out = {b.nodes.value_or(ACCELBENCH_UNKNOWN_COUNT),
            b.leaves.value_or(ACCELBENCH_UNKNOWN_COUNT),
            b.max_depth.value_or(ACCELBENCH_UNKNOWN_COUNT),
            b.memory_bytes.value_or(ACCELBENCH_UNKNOWN_COUNT),
            b.sah_cost.value_or(NAN),
            b.avg_leaf_size.value_or(NAN),
            0,
            nullptr,
            nullptr};
}

void destroy(accelbench_structure* handle) { delete &self(handle); }

const accelbench_structure_desc kStructures[] = {{
    "bvh_plugin",
    "BVH (SAH) as a plugin",
    "our bvh at its defaults, behind the plugin interface: what the interface costs",
    nullptr,
    0,
    ACCELBENCH_COUNTS_TRAVERSAL | ACCELBENCH_WATERTIGHT,
    create,
    build,
    closest_hits,
    any_hits,
    build_stats,
    destroy,
}};

const accelbench_plugin kPlugin = {ACCELBENCH_PLUGIN_ABI_VERSION, "bvh_plugin 1", kStructures, 1};

}  // namespace

extern "C" ACCELBENCH_PLUGIN_EXPORT const accelbench_plugin* accelbench_plugin_entry(void) { return &kPlugin; }
