// A config expanded into combinations (model x accelerator x parameter values), each
// with a stable id; which of them to run (shards, resume) and which to skip (rules).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "accelbench/base/params.h"
#include "config/config.h"

namespace accelbench {

struct Combination {
    size_t model = 0;                          // index into Config::models
    size_t accelerator = 0;                    // index into Config::accelerators
    std::string accel;                         // accelerator name
    std::map<std::string, std::string> given;  // values the config gives (canonical text)
    ParamSet params;                           // every parameter: given or default
    int threads = 1;                           // render threads (one of Config::thread_counts)
    // The ray set this row times (Config::ray_sets); nullopt: the camera row, primary and
    // shadow rays together as the report timed them (`ray_set` = camera).
    std::optional<RaySetKind> ray_set;
    std::string key;    // canonical identity: model key, render settings, accel, params, ray set
    uint64_t hash = 0;  // FNV-1a 64 of key
    std::string id;     // hash as 16 hex digits: the CSV's combo_id
    std::string name;   // for people: "stanford-bunny/kdtree:max_prims=1,max_depth=28"
};

// Expansion: for each model (outer loop) and each accelerator entry, the cartesian
// product of that accelerator's own axes (the first axis varies slowest; a zipped group
// is one axis of tuples; a scalar is a one-value axis), then of the thread counts and the
// ray sets (innermost). An accelerator that declares a
// `threads` parameter and is not given one gets the render thread count (Embree's
// device then uses as many threads as the renderer). Throws ConfigError when two entries
// produce the same combination.
std::vector<Combination> expand(const Config& config);

// The identity text of everything a combination's result depends on besides the code:
// the model, the render settings and the accelerator with all its parameters. Not the
// config's name, file or other entries, so the same measurement has the same id in
// every config.
std::string combination_key(const ModelSpec& model, const RenderSettings& render, const std::string& accel,
                            const ParamSet& params);

// The render settings a combination runs with: the config's, with its thread count.
RenderSettings render_of(const Config& config, const Combination& c);

// "ray_set=ao;samples=4;distance=0.1;seed=1": what of the config's `ray_sets` a set
// depends on (the key's suffix; primary and shadow depend on no parameter).
std::string ray_set_key(RaySetKind kind, const RaySetParams& params);

uint64_t fnv1a64(const std::string& text);
std::string hex16(uint64_t v);

// How much measuring a combination gets: its accelerator entry's `repetitions` /
// `warmup` / `processes`, else its model's, else the config's.
int repetitions_of(const Config& config, const Combination& c);
int warmup_of(const Config& config, const Combination& c);
int processes_of(const Config& config, const Combination& c);

// The reason of the first skip rule that matches, if any.
std::optional<std::string> skip_reason(const Config& config, const Combination& c, uint64_t triangles);

// A stable subset: combination c belongs to shard `index` of `count` when
// c.hash % count == index.
struct Shard {
    uint64_t index = 0;
    uint64_t count = 1;
    bool contains(const Combination& c) const { return c.hash % count == index; }
};

// "i/n" with 0 <= i < n; throws std::invalid_argument with a message otherwise.
Shard parse_shard(const std::string& text);

// From SLURM_ARRAY_TASK_ID / SLURM_ARRAY_TASK_COUNT (the index counted from
// SLURM_ARRAY_TASK_MIN, 0 when unset); nullopt outside a SLURM array job. Throws
// std::invalid_argument on malformed values.
std::optional<Shard> shard_from_slurm();

}  // namespace accelbench
