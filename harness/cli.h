// The accelbench command line: one function per subcommand, argv after the subcommand.
#pragma once

#include <string>
#include <vector>

#include "accelbench/camera.h"
#include "accelbench/renderer.h"
#include "accelbench/scene.h"

namespace accelbench {

class ModelRegistry;

int render_command(int argc, char** argv);
int list_command(int argc, char** argv);
int models_command(int argc, char** argv);

// A model ready to trace: its scene and the view to trace it with.
struct ResolvedModel {
    Scene scene;
    Camera camera;
    Light light;
    std::vector<Vec3> albedo;  // per-triangle colour (procedural scenes); empty: grey
};

// NAME (registry), PATH (a mesh file) or procedural:KIND[,k=v...]; the registry's or the
// procedural scene's own camera and light when it has one, else the auto-fit defaults.
ResolvedModel resolve_model(const std::string& spec, const ModelRegistry& registry, float aspect);

}  // namespace accelbench
