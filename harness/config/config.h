// A benchmark config (configs/*.yaml), read and validated in full before anything runs:
// what its keys mean. The reading itself (positions, types, did-you-mean, every issue at
// once, so a user fixes a config in one pass) is checked_yaml.h's. The keys are
// documented in docs/configs.md.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "accelbench/base/geometry.h"
#include "accelbench/render/ray_sets.h"
#include "accelbench/render/renderer.h"
#include "accelbench/scene/camera.h"
#include "util/checked_yaml.h"

namespace accelbench {

class ModelRegistry;

// A ray file (`rays: {file: ...}`), read once while validating.
struct RaySet {
    std::string path;     // resolved path
    std::string display;  // as written in the config
    std::vector<Ray> rays;
};

// A size change of a registry model for scaling experiments (`decimate: N`,
// `subdivide: LEVELS`); see harness/plan/derived_model.h.
struct ModelTransformSpec {
    enum class Kind { Decimate, Subdivide };
    Kind kind = Kind::Decimate;
    uint64_t amount = 0;  // target triangles, or subdivision levels
    // "decimate=100000" / "subdivide=2": the label suffix after '@' and part of the key.
    std::string text() const;
};

struct ModelSpec {
    // Case: a scene of the extreme-case catalogue (core/accelbench/verify/robustness_cases.h),
    // judged rather than timed.
    enum class Kind { Registry, Path, Procedural, Case };
    Kind kind = Kind::Registry;
    std::string name;           // registry name, path as written, procedural kind, or case id
    std::string resolved_path;  // Kind::Path: relative to the config file's directory
    std::map<std::string, std::string> procedural_params;  // Kind::Procedural: as given
    std::string procedural_canonical;                      // Kind::Procedural: all parameters, defaults filled in
    std::optional<Camera> camera;                          // overrides the registry's / the auto-fit view
    std::shared_ptr<const RaySet> rays;                    // trace these instead of camera rays
    std::optional<ModelTransformSpec> transform;           // Kind::Registry only
    std::optional<int> repetitions, warmup, processes;     // override the config's for this model
    std::string label;                                     // the CSV's `model` column
    std::string key;                                       // config-independent identity (the combination id hashes it)
    SourceMark mark;
    std::string key_path;  // "models[3]"
};

// One parameter axis of an accelerator: a single parameter with its values, or a zipped
// group (`"[max_prims, max_depth]": [[1, 28], [10, 20]]`) whose tuples go together.
struct ParamAxis {
    std::vector<std::string> names;
    std::vector<std::vector<std::string>> values;  // each tuple has names.size() entries
};

struct AcceleratorSpec {
    std::string name;
    std::vector<ParamAxis> axes;                        // in the order written
    std::optional<int> repetitions, warmup, processes;  // override the model's and the config's
    SourceMark mark;
    std::string key_path;  // "accelerators[1]"
};

// A rule that turns matching combinations into `skipped` rows with the reason. Every
// condition given must hold.
struct SkipRule {
    std::optional<std::string> accel;
    std::optional<std::string> model;           // matches the model's label (the `model` column)
    std::optional<uint64_t> triangles_above;    // skip when triangles > this
    std::optional<uint64_t> triangles_below;    // skip when triangles < this
    std::map<std::string, std::string> params;  // canonical text of resolved values
    std::string reason;
    std::string key_path;  // "skip[0]"
};

// `ray_sets`: the ray sets to time, each in a row of its own, and their
// parameters (core/accelbench/render/ray_sets.h).
struct RaySetsSpec {
    std::vector<RaySetKind> sets;  // in the order written; default every set
    RaySetParams params;
};

struct Config {
    std::string path;  // the config file
    std::string dir;   // its directory: relative paths in the config start here
    std::string name;  // `name`, default the file's stem; the CSV's `config` column
    int repetitions = 5;
    int warmup = 1;
    // Child processes that measure each combination, `repetitions` each, pooled into one
    // row: the second pass gives the spread between processes (docs/configs.md).
    int processes = 1;
    // Time the combinations of one model that trace the same rays (ray set and render
    // thread count) in one child process, their repetitions alternating round by round,
    // so that a ratio between two of them is of times taken seconds apart, never minutes
    // (docs/configs.md "Interleaving").
    bool interleave = false;
    double timeout_s = 300;
    // Trace every combination's rays through the `reference` accelerator too and write the
    // error columns; `errors: false` turns it off.
    bool errors = true;
    RenderSettings render;  // shading defaults to off in configs (see docs/configs.md)
    // Absent: one row per combination, primary and shadow rays timed together as the report
    // did (`ray_set` = camera).
    std::optional<RaySetsSpec> ray_sets;
    // `render.threads` as a list (or "1..nproc"): each count is a combination of its own
    // (thread scaling); a single count gives one entry, equal to render.threads.
    std::vector<int> thread_counts = {1};
    // `plugins`: the shared libraries loaded (resolved paths), whose structures are in the
    // registry from then on.
    std::vector<std::string> plugins;
    std::vector<ModelSpec> models;
    std::vector<AcceleratorSpec> accelerators;
    std::vector<SkipRule> skip;
};

// Limits that load_config enforces (docs/configs.md "Limits"): the combinations of one
// config, the primary rays of a model when error columns are measured, and a ray set's
// bytes.
inline constexpr uint64_t kMaxCombinations = 100000;
inline constexpr uint64_t kMaxReferenceRays = uint64_t(1) << 25;  // 33,554,432: 512 MiB of hits
// A ray set's rays and answers: the ray, the reference's hit and the measurement's.
inline constexpr uint64_t kRaySetBytesPerRay = sizeof(Ray) + 2 * sizeof(Hit);  // 64
inline constexpr uint64_t kMaxRaySetBytes = uint64_t(1) << 31;                 // 2 GiB: 33,554,432 rays
// Every set of a model is held at once: one budget for all of them together, the same size
// as one set's, so the largest set allowed alone is also the most held together.
inline constexpr uint64_t kMaxRaySetsTotalBytes = kMaxRaySetBytes;

// Loads the structure plugin at `path` (`--plugin PATH`, `plugins:`) into the accelerator
// registry, with its file's SHA-256 for the rows' provenance. Throws std::runtime_error,
// one line naming the file and the problem.
void load_plugin_file(const std::string& path);

// Reads and validates the config at `path` against the accelerator registry, the
// procedural scene registry and the model registry. Throws ConfigError listing every
// problem found.
Config load_config(const std::string& path, const ModelRegistry& models);

}  // namespace accelbench
