// The factory: accelerators by name, each with its declared parameters. The CLI
// (`accelbench list`) and the YAML harness validate parameters through it.
//
// Adding an accelerator = its file pair, with a static `info()` returning an
// AcceleratorInfo (accelerator.h), and one line in registry.cpp giving its row of the
// structure table (role, family, the variants the report's tables show, slow or not).
// The registry's order is the table's: the analysis shows structures in it.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "accelbench/accel/accelerator.h"
#include "accelbench/base/params.h"

namespace accelbench {

const std::vector<AcceleratorInfo>& accelerator_registry();

// Loads the plugin at `path` (accel/plugin/plugin_accel.h) and appends its structures, so
// that they are found, listed and run like ours; `sha256` is the file's, for the rows'
// provenance. A file loaded already is not loaded again. Throws PluginError (one line,
// naming the file): a plugin that cannot be loaded, or a structure name the registry has
// (built in or from another plugin). Call before looking structures up: entries move.
void register_plugin(const std::string& path, const std::string& sha256);

// The given parameters of each of a structure's table variants: the product of its
// StructureVariants, in declaration order (one empty setting when it declares none).
std::vector<std::map<std::string, std::string>> variant_settings(const AcceleratorInfo& info);

// nullptr if there is no accelerator of that name.
const AcceleratorInfo* find_accelerator(std::string_view name);

// Looks the name up, validates the parameters and creates the (unbuilt) accelerator.
// Throws ParamError naming what is wrong (unknown accelerator: lists the known ones).
std::unique_ptr<Accelerator> make_accelerator(const std::string& name, const std::map<std::string, std::string>& params,
                                              ParamSet* resolved = nullptr);

}  // namespace accelbench
