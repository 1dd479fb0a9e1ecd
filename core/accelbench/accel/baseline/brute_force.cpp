#include "accelbench/accel/baseline/brute_force.h"

#include <stdexcept>

#include "accelbench/base/param_table.h"
#include "accelbench/base/triangle.h"

namespace accelbench {

namespace {

// The parameters, each once: its row and its Config member, whose initializer is the default.
const ParamTable<BruteForce::Config>& brute_force_params() {
    using C = BruteForce::Config;
    static const ParamTable<C> rows = {
        int_param("max_triangles", &C::max_triangles, 0, 1e12, "largest scene it builds without force"),
        bool_param("force", &C::force, "build even above max_triangles"),
    };
    return rows;
}

}  // namespace

AcceleratorInfo BruteForce::info() {
    return {
        "brute_force",
        "tests every triangle for every ray (report section 1.2); refuses scenes above max_triangles unless force=true",
        brute_force_params().specs(), [](const ParamSet& p) { return std::make_unique<BruteForce>(Config::from(p)); },
        fixed_label("brute force")};
}

BruteForce::Config BruteForce::Config::from(const ParamSet& p) { return brute_force_params().from(p); }

void BruteForce::build(const Scene& scene) {
    if (!config_.force && int64_t(scene.triangle_count()) > config_.max_triangles)
        throw std::runtime_error("brute_force refuses scene '" + scene.name + "' with " +
                                 std::to_string(scene.triangle_count()) + " triangles (limit max_triangles=" +
                                 std::to_string(config_.max_triangles) + "; pass force=true to run it anyway)");
    scene_ = &scene;
}

BuildStats BruteForce::build_stats() const {
    BuildStats s;
    s.nodes = 0;
    s.leaves = 0;
    s.max_depth = 0;
    s.memory_bytes = 0;  // no structure beyond the scene itself
    return s;
}

template <class C>
void BruteForce::intersect(const Ray& ray, Hit& hit, C& counters) const {
    const WatertightRay wr(ray);
    float tmax = ray.tmax;
    const uint32_t n = uint32_t(scene_->triangle_count());
    for (uint32_t i = 0; i < n; ++i) {
        counters.prim();
        float t, u, v;
        if (intersect_triangle(wr, scene_->vertex(i, 0), scene_->vertex(i, 1), scene_->vertex(i, 2), ray.tmin, tmax, t,
                               u, v)) {
            tmax = t;
            hit = {i, t, u, v};
        }
    }
}

template <class C>
bool BruteForce::occluded(const Ray& ray, C& counters) const {
    const WatertightRay wr(ray);
    const uint32_t n = uint32_t(scene_->triangle_count());
    for (uint32_t i = 0; i < n; ++i) {
        counters.prim();
        float t, u, v;
        if (intersect_triangle(wr, scene_->vertex(i, 0), scene_->vertex(i, 1), scene_->vertex(i, 2), ray.tmin, ray.tmax,
                               t, u, v))
            return true;
    }
    return false;
}

ACCELBENCH_INSTANTIATE_RAY_QUERIES(BruteForce);

}  // namespace accelbench
