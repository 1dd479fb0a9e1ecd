// `accelbench convert-csv OLD NEW`: a results file written before the measured and global
// columns were renamed (so that no column name repeats), rewritten with the new names and
// checked cell by cell against the old one.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "commands/args.h"
#include "commands/cli.h"
#include "csv/results.h"
#include "util/text.h"

namespace accelbench {

int convert_csv_command(int argc, char** argv) {
    std::string usage =
        "usage: accelbench convert-csv OLD NEW\n"
        "  writes the results file OLD to NEW with the renamed columns' new names (the\n"
        "  parameter columns, between params and status, keep theirs), copies OLD.reps.csv\n"
        "  beside NEW when there is one, then re-reads NEW and checks that every row and value\n"
        "  is OLD's. Adds a missing label (the registry's), fp_mode (ieee: older rows traced in\n"
        "  IEEE mode) and embree_isa (unknown). Renames:";
    for (const RenamedColumn& r : renamed_columns()) usage += concat(" ", r.old_name, " -> ", r.new_name);
    usage += "\n";
    std::vector<std::string> files;
    Args args("convert-csv", usage, argc, argv);
    if (auto code = args.walk([&] {
            if (!args.positional(files)) args.unknown();
        }))
        return *code;
    if (files.size() != 2) return args.error("takes OLD and NEW");
    try {
        const size_t rows = convert_results(files[0], files[1]);
        std::printf("%s: %zu rows converted from %s, every value checked\n", files[1].c_str(), rows, files[0].c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench convert-csv: %s\n", e.what());
        return 1;
    }
    return 0;
}

}  // namespace accelbench
