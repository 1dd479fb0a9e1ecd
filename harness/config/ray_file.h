// Ray files: ray sets a camera cannot make (grazing rays, rays from inside a mesh,
// robustness cases), given to a config model as `rays: {file: ...}`.
//
// Format: CSV, a header line `ox,oy,oz,dx,dy,dz` or `ox,oy,oz,dx,dy,dz,tmax`, then one
// ray per line. Directions need not be normalised; tmin is 0; tmax defaults to infinity.
// Values are read as written, including inf and nan, so robustness experiments can feed
// any ray they like; anything that is not a number is an error naming file:line:column.
#pragma once

#include <string>
#include <vector>

#include "accelbench/base/geometry.h"
#include "config/config.h"

namespace accelbench {

struct RayFileContents {
    std::vector<Ray> rays;
    std::vector<ConfigIssue> issues;  // empty when the file is good; key_path left empty
};

// `display` names the file in messages (the path as the user wrote it). Stops collecting
// issues after a few dozen: a wrong file would otherwise list every line.
RayFileContents read_ray_file(const std::string& path, const std::string& display);

}  // namespace accelbench
