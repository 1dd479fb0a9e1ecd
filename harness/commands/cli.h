// The accelbench command line: one function per subcommand, argv after the subcommand.
#pragma once

#include <string>
#include <vector>

#include "accelbench/render/renderer.h"
#include "accelbench/scene/camera.h"
#include "accelbench/scene/scene.h"
#include "plan/loaded_model.h"

namespace accelbench {

class ModelRegistry;

int render_command(int argc, char** argv);
int list_command(int argc, char** argv);
int models_command(int argc, char** argv);
int columns_command(int argc, char** argv);
int convert_csv_command(int argc, char** argv);

// NAME (registry), PATH (a mesh file) or procedural:KIND[,k=v...], loaded the way the
// harness loads a config's model (load_model: the registry's or procedural scene's own
// camera and light when it has one, else the auto-fit defaults for the image's aspect).
LoadedModel resolve_model(const std::string& spec, const ModelRegistry& registry, const RenderSettings& render);

}  // namespace accelbench
