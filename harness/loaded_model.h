// A config model made ready to trace: its triangles, the view and light to trace them
// with, and its ray file if it has one. Loaded once per model and shared by every
// accelerator measured on it.
#pragma once

#include <memory>
#include <vector>

#include "accelbench/camera.h"
#include "accelbench/renderer.h"
#include "accelbench/scene.h"
#include "config.h"

namespace accelbench {

class ModelRegistry;

struct LoadedModel {
    Scene scene;
    Camera camera;
    Light light;
    std::vector<Vec3> albedo;            // per-triangle colours (procedural scenes); may be empty
    std::shared_ptr<const RaySet> rays;  // traced instead of the camera's rays when set
};

// The view: the config's camera, else the registry's or procedural scene's own, else
// Camera::fit for the image's aspect. The light: the registry's or procedural scene's,
// else default_light for that view. Throws std::runtime_error (file missing, checksum
// mismatch, bad mesh) naming the model.
LoadedModel load_model(const ModelSpec& spec, const ModelRegistry& registry, const RenderSettings& render);

// The triangle count when it is known without loading (untransformed registry models);
// nullopt otherwise.
std::optional<uint64_t> known_triangles(const ModelSpec& spec, const ModelRegistry& registry);

}  // namespace accelbench
