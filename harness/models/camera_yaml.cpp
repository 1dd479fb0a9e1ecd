#include "models/camera_yaml.h"

namespace accelbench {

std::optional<Camera> read_camera(Checker& c, const YAML::Node& n, const std::string& path) {
    Fields f(c, n, path, {"eye", "look_at", "up", "fov"});
    if (!f.ok()) return std::nullopt;
    Camera cam;
    bool ok = true;
    auto vec = [&](const char* key, Vec3& out, bool required) {
        const auto* e = required ? f.require(key) : f.find(key);
        if (!e) {
            ok &= !required;
            return;
        }
        if (auto v = read_vec3(c, e->value, f.child(key))) out = *v;
        else ok = false;
    };
    vec("eye", cam.eye, true);
    vec("look_at", cam.look_at, true);
    vec("up", cam.up, false);
    if (auto* e = f.find("fov")) {
        if (auto v = read_float(c, e->value, f.child("fov"), 0, 179, true)) cam.fov_deg = *v;
        else ok = false;
    }
    if (!ok) return std::nullopt;
    const Vec3 view = cam.look_at - cam.eye;
    if (dot(view, view) == 0.0f) {
        c.error(n, path, "eye and look_at are the same point: the camera has no view direction");
        return std::nullopt;
    }
    const Vec3 side = cross(view, cam.up);
    if (dot(side, side) == 0.0f) {
        c.error(n, path, "up is parallel to the view direction (look_at - eye)");
        return std::nullopt;
    }
    return cam;
}

}  // namespace accelbench
