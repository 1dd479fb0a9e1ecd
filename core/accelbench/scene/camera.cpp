#include "accelbench/scene/camera.h"

#include <cmath>
#include <stdexcept>

namespace accelbench {

namespace {

constexpr float kDegToRad = 3.14159265358979f / 180.0f;

// An up vector that is not parallel to `forward`: the given one unless the view runs
// (nearly) along it, when the cross product that makes the image's right axis would
// vanish; then a z axis stands in (any direction across the view would do).
Vec3 usable_up(Vec3 forward, Vec3 up) {
    const Vec3 f = normalize(forward);
    Vec3 u = normalize(up);
    if (std::fabs(dot(f, u)) > 0.999f) u = f.y > 0 ? Vec3{0, 0, 1} : Vec3{0, 0, -1};
    return u;
}

}  // namespace

Camera Camera::fit(const Bounds3& bounds, float aspect, Vec3 direction, float fov_deg) {
    if (!(fov_deg > 0.0f && fov_deg < 180.0f)) throw std::invalid_argument("Camera::fit: fov_deg must lie in (0, 180)");
    if (!(aspect > 0.0f)) throw std::invalid_argument("Camera::fit: aspect must be positive");
    if (!(length(direction) > 0.0f) || !is_finite(direction))
        throw std::invalid_argument("Camera::fit: the view direction must be a finite non-zero vector");

    // An empty scene still gets a valid camera (around the origin).
    const Vec3 centre = bounds.empty() ? Vec3{} : bounds.center();
    float radius = bounds.empty() ? 1.0f : 0.5f * length(bounds.diagonal());
    if (!(radius > 0.0f)) radius = 1.0f;  // a single point

    // The sphere fills the narrower of the two fields of view: the vertical one for
    // landscape images, the horizontal one for portrait images. A sphere of radius r seen
    // from distance d subtends a half-angle asin(r / d).
    const float half_v = 0.5f * fov_deg * kDegToRad;
    const float half_h = std::atan(std::tan(half_v) * aspect);
    const float half = std::min(half_v, half_h);
    const float distance = radius / std::sin(half);

    Camera c;
    c.look_at = centre;
    c.eye = centre - normalize(direction) * distance;
    c.up = usable_up(direction, {0, 1, 0});
    c.fov_deg = fov_deg;
    return c;
}

CameraRays::CameraRays(const Camera& camera, int width, int height) : eye_(camera.eye) {
    if (width <= 0 || height <= 0) throw std::invalid_argument("CameraRays: the image size must be positive");
    const Vec3 view = camera.look_at - camera.eye;
    if (!(length(view) > 0.0f) || !is_finite(view))
        throw std::invalid_argument("CameraRays: eye and look_at must be distinct finite points");
    const Vec3 forward = normalize(view);
    const Vec3 right = normalize(cross(forward, usable_up(forward, camera.up)));
    const Vec3 up = cross(right, forward);

    // The image plane sits at distance 1 in front of the eye; its half-height is
    // tan(fov/2) and its half-width follows from the view's aspect ratio (the image's,
    // square pixels, unless the camera declares its own).
    if (!(camera.aspect >= 0.0f) || !std::isfinite(camera.aspect))
        throw std::invalid_argument("CameraRays: the camera's aspect must be 0 (the image's) or positive");
    const float half_h = std::tan(0.5f * camera.fov_deg * kDegToRad);
    const float half_w = half_h * (camera.aspect > 0.0f ? camera.aspect : float(width) / float(height));
    corner_ = forward - right * half_w + up * half_h;
    right_ = right * (2.0f * half_w / float(width));
    down_ = up * (-2.0f * half_h / float(height));
}

Ray CameraRays::primary(float x, float y) const {
    return {eye_, 0.0f, normalize(corner_ + right_ * x + down_ * y), kInfinity};
}

}  // namespace accelbench
