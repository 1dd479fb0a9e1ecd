#include "accelbench/scene/scene.h"

#include <stdexcept>
#include <string>

namespace accelbench {

void Scene::finalize() {
    // Every vertex, used by a face or not: one policy with the mesh readers (a vertex that
    // is not finite is a corrupt input, whether or not a face refers to it).
    for (size_t vi = 0; vi < vertices.size(); ++vi) {
        if (!is_finite(vertices[vi]))
            throw std::runtime_error("scene '" + name + "': vertex " + std::to_string(vi) +
                                     " is not finite (used by a face or not, such a vertex is refused)");
        if (!within_coordinate_limit(vertices[vi]))
            throw std::runtime_error("scene '" + name + "': vertex " + std::to_string(vi) +
                                     " has a coordinate of magnitude 1.844e18 or more "
                                     "(the limit kMaxCoordinate, Embree's FLT_LARGE)");
    }
    const size_t n = triangles.size();
    prim_bounds.resize(n);
    centroids.resize(n);
    bounds = Bounds3{};
    for (size_t i = 0; i < n; ++i) {
        Bounds3 b;
        for (int k = 0; k < 3; ++k) {
            const uint32_t vi = triangles[i][k];
            if (vi >= vertices.size())
                throw std::runtime_error("scene '" + name + "': face " + std::to_string(i) + " uses vertex index " +
                                         std::to_string(vi) + " but there are only " + std::to_string(vertices.size()) +
                                         " vertices");
            if (!is_finite(vertices[vi]))
                throw std::runtime_error("scene '" + name + "': face " + std::to_string(i) + " uses vertex " +
                                         std::to_string(vi) + " whose coordinates are not finite");
            const Vec3 p = vertices[vi];
            if (!within_coordinate_limit(p))
                throw std::runtime_error("scene '" + name + "': face " + std::to_string(i) + " uses vertex " +
                                         std::to_string(vi) +
                                         " with a coordinate of magnitude 1.844e18 or more "
                                         "(the limit kMaxCoordinate, Embree's FLT_LARGE)");
            b.extend(p);
        }
        prim_bounds[i] = b;
        centroids[i] = b.center();
        bounds.extend(b);
    }
}

}  // namespace accelbench
