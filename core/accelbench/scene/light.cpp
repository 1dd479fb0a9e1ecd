#include "accelbench/scene/light.h"

#include <algorithm>

namespace accelbench {

Light default_light(const Bounds3& scene_bounds, const Camera& camera) {
    const Vec3 centre = scene_bounds.empty() ? camera.look_at : scene_bounds.center();
    float radius = scene_bounds.empty() ? 0.0f : 0.5f * length(scene_bounds.diagonal());
    if (!(radius > 0.0f)) radius = std::max(1e-3f, length(camera.eye - camera.look_at));
    // The camera's frame.
    const Vec3 forward = normalize(camera.look_at - camera.eye);
    Vec3 right = cross(forward, camera.up);
    right = length(right) > 0.0f ? normalize(right) : Vec3{1, 0, 0};
    const Vec3 up = cross(right, forward);
    // Behind the viewer (so the faces the camera sees are lit), to the right and well
    // above (so shadows fall visibly down and to the left of the objects): about 50 degrees
    // off the view direction and five scene radii from the centre, which puts it behind
    // the eye of a Camera::fit view (2.6 radii away at 45 degrees).
    const Vec3 dir = normalize(forward * -1.0f + right * 0.7f + up * 1.1f);
    return {centre + dir * (5.0f * radius)};
}

}  // namespace accelbench
