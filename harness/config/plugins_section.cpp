// `plugins: [PATH, ...]`: shared libraries of structures (accelbench_plugin.h), loaded
// before `accelerators` is read so that their structures can be named there, `all`
// included. A path is relative to the config's directory.
#include <yaml-cpp/yaml.h>

#include "accelbench/accel/registry.h"
#include "config/config_sections.h"
#include "util/sha256.h"

namespace accelbench {

void load_plugin_file(const std::string& path) {
    std::string sha256;
    try {
        sha256 = sha256_file(path);
    } catch (const std::runtime_error&) {
        sha256.clear();  // load_plugin says what is wrong with the file, in its words
    }
    register_plugin(path, sha256);
}

void read_plugins(ConfigReader& r, const YAML::Node& n) {
    read_list(r.c, n, "plugins", [&](const YAML::Node& item, const std::string& p) {
        const auto path = read_string(r.c, item, p);
        if (!path) return;
        const std::string file = r.resolve(*path);
        try {
            load_plugin_file(file);
            r.cfg.plugins.push_back(file);
        } catch (const std::runtime_error& e) {
            r.c.error(item, p, e.what());
        }
    });
}

}  // namespace accelbench
