// Pinhole camera: where primary rays come from.
#pragma once

#include "accelbench/base/geometry.h"

namespace accelbench {

struct Camera {
    Vec3 eye{0, 0, 5};
    Vec3 look_at{0, 0, 0};
    Vec3 up{0, 1, 0};
    float fov_deg = 45.0f;  // vertical field of view
    // Width over height of the field of view; 0 (the default): the image's, so pixels are
    // square. A glTF camera may declare its own (aspectRatio), which then holds whatever
    // the image's size.
    float aspect = 0.0f;

    // The default view of a model: looks at the centre of `bounds` along `direction`
    // from just far enough that the bounding sphere fills the vertical field of view, so
    // every model fills the image the same way whatever its units.
    static Camera fit(const Bounds3& bounds, float aspect, Vec3 direction = {-0.3f, -0.25f, -1.0f},
                      float fov_deg = 45.0f);
};

// A camera prepared for one image size: turns pixel coordinates into primary rays.
class CameraRays {
public:
    CameraRays(const Camera& camera, int width, int height);
    // (x, y) in pixels, (0, 0) the top-left corner of the image, (width, height) the
    // bottom-right; pixel centres are at +0.5. Directions are normalised.
    Ray primary(float x, float y) const;

private:
    Vec3 eye_, corner_, right_, down_;
};

}  // namespace accelbench
