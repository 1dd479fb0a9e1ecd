// A structure from a plugin (plugin/accelbench_plugin.h), wrapped in an ordinary
// Accelerator: past the registry nothing knows where a structure came from. Loading a
// plugin reads and checks its description (ABI version, names, parameter tables) and turns
// each structure descriptor into an AcceleratorInfo; refusals are one line naming the file.
#pragma once

#include <string>
#include <vector>

#include "accelbench/accel/accelerator.h"

namespace accelbench {

// A plugin that cannot be used: "plugin FILE: problem", one line.
struct PluginError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// A plugin's structures, ready for the registry (accelerator_registry's register_plugin).
struct LoadedPlugin {
    std::string path;     // as given
    std::string version;  // the plugin's own version string
    std::vector<AcceleratorInfo> structures;
};

// dlopen()s the shared library at `path` (kept loaded for the life of the process) and
// reads its description. `sha256` (of the file) goes into every structure's PluginSource.
// Throws PluginError: not a shared library, no entry point, another ABI version, no
// structure, a name, label or parameter table that does not parse, a name twice.
LoadedPlugin load_plugin(const std::string& path, const std::string& sha256);

}  // namespace accelbench
