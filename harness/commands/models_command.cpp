// `accelbench models`: the model registry, where each file was found (--fetch: download
// what is missing).
#include <cstdio>
#include <exception>
#include <string>

#include "commands/args.h"
#include "commands/cli.h"
#include "models/model_registry.h"

namespace accelbench {

int models_command(int argc, char** argv) {
    bool fetch = false;
    Args args("models",
              "usage: accelbench models [--fetch]\n"
              "  the model registry (configs/models.yaml): each model, where its file was found;\n"
              "  --fetch downloads the missing ones. Exit 1 when one is still missing\n",
              argc, argv);
    if (auto code = args.walk([&] { fetch = args.flag("--fetch") || args.unknown(); })) return *code;
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
