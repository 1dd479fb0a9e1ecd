// `accelbench models`: the model registry, where each file was found (--fetch: download
// what is missing).
#include "commands/cli.h"

#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "models/model_registry.h"

namespace accelbench {

int models_command(int argc, char** argv) {
    bool fetch = false;
    for (int i = 0; i < argc; ++i) {
        if (std::strcmp(argv[i], "--fetch") == 0) fetch = true;
        else {
            std::fprintf(stderr, "accelbench models: unknown option '%s'\nusage: accelbench models [--fetch]\n",
                         argv[i]);
            return 2;
        }
    }
    int missing = 0;
    try {
        ModelRegistry registry = ModelRegistry::load_default();
        std::printf("%-20s %10s %10s  %-10s %s\n", "model", "triangles", "vertices", "found", "path");
        for (const auto& e : registry.entries()) {
            ModelLocation loc;
            try {
                loc = fetch ? registry.fetch(e) : registry.locate(e);
            } catch (const std::exception& ex) {
                loc = {"", std::string("error: ") + ex.what()};
            }
            if (loc.path.empty()) ++missing;
            std::printf("%-20s %10llu %10llu  %-10s %s\n", e.name.c_str(), (unsigned long long)e.triangles,
                        (unsigned long long)e.vertices, loc.path.empty() ? "missing" : loc.where.c_str(),
                        loc.path.empty() ? (loc.where == "missing" ? "(run `make models`)" : loc.where.c_str())
                                         : loc.path.c_str());
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench models: %s\n", e.what());
        return 2;
    }
    return missing == 0 ? 0 : 1;
}

}  // namespace accelbench
