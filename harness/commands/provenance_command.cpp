// `accelbench provenance`: the provenance columns this build writes into every results
// row, NAME=VALUE (the main job's reproduce/runs.py compares them with an unfinished run's).
#include <cstdio>

#include "commands/args.h"
#include "commands/cli.h"
#include "csv/provenance.h"

namespace accelbench {

int provenance_command(int argc, char** argv) {
    Args args("provenance",
              "usage: accelbench provenance\n"
              "  prints the provenance columns this build writes into every results row, NAME=VALUE\n",
              argc, argv);
    if (auto code = args.walk([&] { args.unknown(); })) return *code;
    for (const auto& [name, value] : provenance_values()) std::printf("%s=%s\n", name.c_str(), value.c_str());
    return 0;
}

}  // namespace accelbench
