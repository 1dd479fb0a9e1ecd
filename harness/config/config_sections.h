// Reading a config, one file per group of top-level keys: config.cpp reads the run's own
// settings (name, repetitions, warmup, timeout_s, errors) and checks the limits,
// render_section.cpp `render`, `ray_sets` and `rays`, models_section.cpp `models`,
// accelerators_section.cpp `accelerators`, skip_section.cpp `skip`; param_values.cpp
// reads a parameter's values (lists, ranges, zipped groups) for the sections that take
// them. What they share while one file is read is a ConfigReader. Internal to config/.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "accelbench/base/params.h"
#include "config/config.h"
#include "util/checked_yaml.h"

namespace accelbench {

struct AcceleratorInfo;

// The state of reading one config: its issues so far, the config as read so far (a later
// section may look at an earlier one's result: skip rules name models), and what one
// section leaves for another.
struct ConfigReader {
    ConfigReader(const std::string& path, const ModelRegistry& registry);

    Checker c;
    Config cfg;
    const ModelRegistry& registry;
    std::shared_ptr<const RaySet> default_rays;                      // the top-level `rays`
    std::map<std::string, std::shared_ptr<const RaySet>> ray_files;  // by resolved path: read once

    // A path of the config, relative to its directory unless absolute.
    std::string resolve(const std::string& p) const;
};

// ---- the sections --------------------------------------------------------------------

void read_plugins(ConfigReader& r, const YAML::Node& n);   // plugins_section.cpp
void read_render(ConfigReader& r, const YAML::Node& n);    // render_section.cpp
void read_ray_sets(ConfigReader& r, const YAML::Node& n);  // render_section.cpp
// `rays: {file: ...}`, top-level or a model's: the ray file, read once per path.
std::shared_ptr<const RaySet> read_rays(ConfigReader& r, const YAML::Node& n, const std::string& path);
void read_models(ConfigReader& r, const YAML::Node& n);        // models_section.cpp
void read_accelerators(ConfigReader& r, const YAML::Node& n);  // accelerators_section.cpp
void read_skip_rules(ConfigReader& r, const YAML::Node& n);    // skip_section.cpp

// `repetitions` and `warmup` of a model or an accelerator entry (for the slow ones);
// false when one is wrong.
bool read_effort(ConfigReader& r, const Fields& f, std::optional<int>& repetitions, std::optional<int>& warmup,
                 std::optional<int>& processes);

// ---- parameter values (param_values.cpp) ----------------------------------------------

const ParamSpec* find_spec(const std::vector<ParamSpec>& specs, const std::string& name);
std::vector<std::string> spec_names(const std::vector<ParamSpec>& specs);
std::string format_float(double v);

// One parameter value, validated against its declaration: its canonical text (so that 1.0
// and 1 for a float name the same combination). `owner` is the accelerator or procedural
// scene.
std::optional<std::string> read_param_value(Checker& c, const YAML::Node& n, const std::string& path,
                                            const std::string& owner, const ParamSpec& spec);

// An accelerator's `params` mapping (`node`, at key path `base`, e.g.
// "accelerators[2].kdtree") into axes: each key a parameter or a zipped group
// ("[max_prims, max_depth]"), each value one value, a list, or a range. False when
// something is wrong (its issues are in `c`).
bool read_param_axes(Checker& c, const YAML::Node& node, const std::string& base, const AcceleratorInfo& info,
                     std::vector<ParamAxis>& axes);

}  // namespace accelbench
