// The generators of the extreme-case catalogue, one per case or family of cases; the
// catalogue (robustness_cases.cpp) lists them with their ids.
#pragma once

#include <string>

#include "accelbench/verify/robustness_cases.h"

namespace accelbench::robustness {

// Cases 1-3: closed meshes scaled by `scale`, then translated by `offset` on every axis.
RobustnessCase closed_meshes(std::string id, std::string name, float scale, float offset);
RobustnessCase origins_on_box_faces();
RobustnessCase signed_zero_directions();
RobustnessCase tiny_direction_components();
RobustnessCase grazing_rays();
RobustnessCase degenerate_triangles();
RobustnessCase copies_and_equal_centroids();
RobustnessCase flat_scene();
RobustnessCase cluster_and_outlier();
RobustnessCase coplanar_split_planes();
RobustnessCase overlapping_coplanar();
// Case 14: bad input of `variant` 0-4 (a-e): NaN, Inf, huge vertex, index out of range,
// unused NaN vertex.
RobustnessCase bad_input(std::string id, std::string name, std::string requirement, int variant);
RobustnessCase invalid_rays();
RobustnessCase nested_shells();
RobustnessCase distant_camera();
RobustnessCase deep_tree();

}  // namespace accelbench::robustness
