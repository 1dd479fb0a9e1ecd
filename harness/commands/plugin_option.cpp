// `--plugin PATH` of run, list and render: the structures of a plugin
// (accelbench_plugin.h) join the registry before the command looks anything up.
#include <cstdio>

#include "commands/cli.h"
#include "config/config.h"

namespace accelbench {

std::optional<int> load_plugins(const char* command, const std::vector<std::string>& paths) {
    for (const std::string& path : paths) {
        try {
            load_plugin_file(path);
        } catch (const std::runtime_error& e) {
            std::fprintf(stderr, "accelbench %s: %s\n", command, e.what());
            return 2;
        }
    }
    return std::nullopt;
}

}  // namespace accelbench
