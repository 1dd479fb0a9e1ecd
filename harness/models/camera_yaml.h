// The one reader of a `camera:` mapping, with one set of rules for the model registry
// (configs/models.yaml) and a config's model entries: {eye, look_at, up, fov}, eye and
// look_at required, fov vertical in degrees in (0, 179], a view direction that is not
// zero and not parallel to up.
#pragma once

#include <optional>
#include <string>

#include "accelbench/scene/camera.h"
#include "util/checked_yaml.h"

namespace accelbench {

// The camera, or nullopt with its issues in `c`.
std::optional<Camera> read_camera(Checker& c, const YAML::Node& n, const std::string& path);

}  // namespace accelbench
