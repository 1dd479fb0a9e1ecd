#include "loaded_model.h"

#include <stdexcept>

#include "accelbench/mesh_io.h"
#include "accelbench/procedural.h"
#include "derived_model.h"
#include "model_registry.h"

namespace accelbench {

LoadedModel load_model(const ModelSpec& spec, const ModelRegistry& registry, const RenderSettings& render) {
    LoadedModel m;
    std::optional<Camera> camera = spec.camera;
    std::optional<Light> light;
    switch (spec.kind) {
        case ModelSpec::Kind::Registry: {
            const ModelEntry* entry = registry.find(spec.name);
            if (!entry) throw std::runtime_error("model '" + spec.name + "' is not in the model registry");
            m.scene = spec.transform ? load_derived_scene(registry, *entry, *spec.transform) : registry.load_scene(*entry);
            if (!camera) camera = entry->camera;
            light = entry->light;
            break;
        }
        case ModelSpec::Kind::Path:
            m.scene = load_mesh(spec.resolved_path);
            break;
        case ModelSpec::Kind::Procedural: {
            ProceduralScene p = generate_procedural(spec.name, spec.procedural_params);
            m.scene = std::move(p.scene);
            m.albedo = std::move(p.albedo);
            if (!camera) camera = p.camera;
            light = p.light;
            break;
        }
    }
    m.camera = camera ? *camera : Camera::fit(m.scene.bounds, float(render.width) / float(render.height));
    m.light = light ? *light : default_light(m.scene.bounds, m.camera);
    m.rays = spec.rays;
    return m;
}

std::optional<uint64_t> known_triangles(const ModelSpec& spec, const ModelRegistry& registry) {
    // A transformed model's count is known once it is made (decimation stops near, not at,
    // its target; subdivision drops faces the half-edge mesh refuses).
    if (spec.kind != ModelSpec::Kind::Registry || spec.transform) return std::nullopt;
    const ModelEntry* entry = registry.find(spec.name);
    return entry ? std::optional<uint64_t>(entry->triangles) : std::nullopt;
}

}  // namespace accelbench
