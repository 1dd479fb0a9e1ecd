// The catalogue: the cases in order, each made on demand and completed with the
// reference's answers.
#include "accelbench/verify/robustness_cases.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "accelbench/accel/baseline/reference.h"
#include "accelbench/base/unknown_name.h"
#include "accelbench/verify/robustness_generators.h"

namespace accelbench {

using namespace robustness;

namespace {

// Finalizes a valid case's scene and records the reference's answers.
RobustnessCase with_reference(RobustnessCase c) {
    if (c.expects_rejection()) return c;
    if (c.scene.prim_bounds.size() != c.scene.triangle_count()) c.scene.finalize();
    const ParamSet defaults = resolve_params("reference", ReferenceAccel::info().params, {});
    ReferenceAccel reference(ReferenceAccel::Config::from(defaults));
    reference.build(c.scene);
    c.reference_hits.resize(c.rays.size());
    reference.closest_hits(c.rays, c.reference_hits);
    return c;
}

const std::string kRejected =
    "rejected by Scene::finalize() with a message naming the bad vertex (an index: face 5), whatever the accelerator";

}  // namespace

const std::vector<RobustnessCaseEntry>& robustness_case_list() {
    static const std::vector<RobustnessCaseEntry> list = {
        {"1", [] { return closed_meshes("1", "closed-meshes", 1.0f, 0.0f); }},
        {"2a", [] { return closed_meshes("2a", "closed-meshes-at-1.5e5", 1.0f, 1.5e5f); }},
        {"2b", [] { return closed_meshes("2b", "closed-meshes-at-1e6", 1.0f, 1e6f); }},
        {"2c", [] { return closed_meshes("2c", "closed-meshes-at-1e7", 1.0f, 1e7f); }},
        {"3a", [] { return closed_meshes("3a", "closed-meshes-scaled-1e-6", 1e-6f, 0.0f); }},
        // 2^-64: coordinates ~1e-19, so the edge functions (products of two coordinates)
        // are float denormals; 2^-90: they underflow to zero.
        {"3b", [] { return closed_meshes("3b", "closed-meshes-scaled-2^-64", std::ldexp(1.0f, -64), 0.0f); }},
        {"3c", [] { return closed_meshes("3c", "closed-meshes-scaled-2^-90", std::ldexp(1.0f, -90), 0.0f); }},
        {"4", origins_on_box_faces},
        {"5", signed_zero_directions},
        {"6", tiny_direction_components},
        {"7", grazing_rays},
        {"8", degenerate_triangles},
        {"9", copies_and_equal_centroids},
        {"10", flat_scene},
        {"11", cluster_and_outlier},
        {"12", coplanar_split_planes},
        {"13", overlapping_coplanar},
        {"14a", [] { return bad_input("14a", "nan-vertex", "a face using a NaN vertex is " + kRejected, 0); }},
        {"14b", [] { return bad_input("14b", "inf-vertex", "a face using an infinite vertex is " + kRejected, 1); }},
        {"14c",
         [] {
             return bad_input("14c", "huge-vertex",
                              "a face using a vertex with a coordinate of 2e19 (>= kMaxCoordinate = 1.844e18, "
                              "Embree's limit) is " +
                                  kRejected,
                              2);
         }},
        {"14d",
         [] {
             return bad_input("14d", "index-out-of-range", "a face with an index past the vertex array is " + kRejected,
                              3);
         }},
        {"14e",
         [] {
             return bad_input("14e", "unused-nan-vertex",
                              "a NaN vertex that no face uses is rejected by Scene::finalize() with a message naming "
                              "the vertex, as the mesh readers refuse it (one policy, docs/configs.md)",
                              4);
         }},
        {"15", invalid_rays},
        {"16", nested_shells},
        {"17", distant_camera},
        {"18", deep_tree},
    };
    return list;
}

namespace {

const RobustnessCaseEntry& find_case(const std::string& id) {
    for (const auto& entry : robustness_case_list())
        if (entry.id == id) return entry;
    throw std::invalid_argument(
        unknown_name("robustness case", id, names_of(robustness_case_list(), &RobustnessCaseEntry::id)));
}

}  // namespace

std::string robustness_case_name(const std::string& id) { return find_case(id).make().name; }

RobustnessCase make_robustness_case(const std::string& id) { return with_reference(find_case(id).make()); }

std::vector<RobustnessCase> robustness_catalogue() {
    std::vector<RobustnessCase> cases;
    for (const auto& entry : robustness_case_list()) cases.push_back(with_reference(entry.make()));
    return cases;
}

}  // namespace accelbench
