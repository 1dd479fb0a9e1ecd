// A config model made ready to trace: its triangles, the view and light to trace them
// with, and its ray file if it has one. Loaded once per model and shared by every
// accelerator measured on it.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "accelbench/render/renderer.h"
#include "accelbench/scene/camera.h"
#include "accelbench/scene/scene.h"
#include "config/config.h"

namespace accelbench {

class ModelRegistry;
class WireReader;
class WireWriter;

struct RobustnessCase;

// What the `reference` accelerator answers for a model's rays: the error columns
// of every combination on the model are measured against it. Traced once per model, when
// the model is prepared (runner.cpp), before any combination's measurement.
struct ReferenceAnswers {
    std::vector<Hit> hits;       // one per primary ray (TraceOutput::primary_hits)
    std::optional<Image> image;  // image runs (shading on) only
    double seconds = 0;          // build and trace, for the progress line
};

struct LoadedModel {
    Scene scene;
    Camera camera;
    Light light;
    std::vector<Vec3> albedo;            // per-triangle colours (procedural scenes); may be empty
    std::shared_ptr<const RaySet> rays;  // traced instead of the camera's rays when set
    // ModelSpec::Kind::Case: the case, complete with its reference answers. Its scene is
    // also `scene`, unfinalized when the case expects it to be rejected; such a model has
    // no view and is judged (judge_case), never timed.
    std::shared_ptr<const RobustnessCase> robustness_case;
    std::shared_ptr<const ReferenceAnswers> reference;  // set by add_reference_answers
    // The config's ray sets, with the reference's answers; set by add_ray_sets.
    std::shared_ptr<const std::vector<GeneratedRaySet>> ray_sets;
    // The sets that could not be made (std::bad_alloc, a bad parameter), with why: their
    // rows are errors, the model's other sets still run.
    std::map<RaySetKind, std::string> ray_set_errors;

    // The set of that kind; throws std::logic_error if it was not made.
    const GeneratedRaySet& ray_set(RaySetKind kind) const;
};

// Traces the model's rays (its ray file, else its camera's) through `accel`.
TraceOutput trace_model(const Accelerator& accel, const LoadedModel& model, const TraceRequest& request);

// Builds the `reference` accelerator on the model, traces the model's rays through it
// with the render settings, keeping every primary hit (and the image, for image runs;
// no counters, no shadow rays unless an image shows them), and keeps the answers in
// model.reference; the structure itself is freed. Measurements compare their second
// counting render with these (measure.h).
void add_reference_answers(LoadedModel& model, const RenderSettings& render);

// Makes the config's ray sets for the model (make_ray_sets: from its camera's rays, the
// reference's hits and its light), once per model when it is prepared, outside anything
// timed, so every accelerator traces the same rays. Prints each set's size and hash. A set
// that cannot be made is left out with its reason in model.ray_set_errors; the others
// are made all the same.
void add_ray_sets(LoadedModel& model, const RenderSettings& render, const RaySetsSpec& spec);

// A prepared model (loaded, with its reference answers and ray sets when made) in the
// wire form (util/wire.h), to bring it from the child process that prepares it under the
// time limit (runner.cpp) to the parent: the scene's vertices and triangles (finalized
// again on arrival), view, light, colours, reference answers and ray sets. The ray file is
// not sent: it is the config's (spec.rays), which the parent has. A robustness case is
// never sent (std::logic_error): it is made in the parent. The reader throws
// std::runtime_error for bytes that end early.
void put_loaded_model(WireWriter& w, const LoadedModel& model);
LoadedModel take_loaded_model(WireReader& r, const ModelSpec& spec);

// The view: the config's camera, else the registry's, procedural scene's or glTF file's own, else
// Camera::fit for the image's aspect. The light: the registry's or procedural scene's,
// else default_light for that view. Throws std::runtime_error (file missing, checksum
// mismatch, bad mesh) naming the model.
LoadedModel load_model(const ModelSpec& spec, const ModelRegistry& registry, const RenderSettings& render);

// The triangle count when it is known without loading (untransformed registry models);
// nullopt otherwise.
std::optional<uint64_t> known_triangles(const ModelSpec& spec, const ModelRegistry& registry);

}  // namespace accelbench
