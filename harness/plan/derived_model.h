// Registry models at other sizes (`{name: stanford-dragon, decimate: 100000}`), made by
// core/accelbench/scene/mesh_transform.h and cached on disk, because decimating the 871k dragon
// takes far longer than loading the result.
//
// The cache file is <project>/models/derived/<name>-<decimate|subdivide>-<N>.ply, a binary
// PLY whose header comments record the source's sha256 and the transform's version. A
// file whose comments do not match (a changed source model, a changed transform) is
// rebuilt, never used.
#pragma once

#include <string>

#include "accelbench/scene/scene.h"
#include "config/config.h"
#include "models/model_registry.h"

namespace accelbench {

// Where the transformed model is cached.
std::string derived_model_path(const ModelRegistry& registry, const ModelEntry& entry, const ModelTransformSpec& t);

// The transformed model: from the cache when it is valid, else made from the registry
// model, written to the cache (atomically: concurrent shards never read a partial file)
// and returned. Reports on stderr when it transforms and how many faces the half-edge
// mesh refused (detached with their own vertex copies and kept, MeshTransformInfo). The
// scene's name is "<name>@<transform>".
Scene load_derived_scene(const ModelRegistry& registry, const ModelEntry& entry, const ModelTransformSpec& t);

}  // namespace accelbench
