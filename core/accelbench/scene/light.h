// The scene's point light (the report's setup, section 5: one point light, one shadow ray
// per hit toward it). A procedural scene may bring its own; otherwise the default one.
#pragma once

#include "accelbench/base/geometry.h"
#include "accelbench/scene/camera.h"

namespace accelbench {

struct Light {
    Vec3 position;
};

// The default light: above and behind the camera's right shoulder, at a distance
// proportional to the scene, so the default view shows lit faces and cast shadows.
Light default_light(const Bounds3& scene_bounds, const Camera& camera);

}  // namespace accelbench
