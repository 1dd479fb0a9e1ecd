// A scene as every structure sees it: flat vertex and index arrays, plus what builders
// need again and again (per-triangle bounds and centroids, the scene bounds), computed
// once by finalize().
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "accelbench/base/geometry.h"

namespace accelbench {

struct Scene {
    std::string name;
    std::vector<Vec3> vertices;
    std::vector<std::array<uint32_t, 3>> triangles;

    // Derived by finalize(); structures read these, never recompute them.
    std::vector<Bounds3> prim_bounds;
    std::vector<Vec3> centroids;
    Bounds3 bounds;

    size_t triangle_count() const { return triangles.size(); }
    size_t vertex_count() const { return vertices.size(); }
    Vec3 vertex(uint32_t prim, int corner) const { return vertices[triangles[prim][corner]]; }

    // Checks the input and computes the derived arrays. Bad input is rejected, not
    // repaired: a vertex that is not finite or has a coordinate of magnitude
    // kMaxCoordinate or more, used by a face or not (the mesh readers' policy too:
    // docs/configs.md, "Mesh files"), throws std::runtime_error naming the vertex; an
    // index out of range names the face. So every accelerator (Embree included, which
    // would silently drop such faces) sees exactly the same triangles.
    void finalize();
};

}  // namespace accelbench
