// `accelbench convert-csv OLD NEW`: a results file written before the measured and global
// columns were renamed (so that no column name repeats), rewritten with the new names and
// checked cell by cell against the old one.
#include <cstdio>
#include <exception>
#include <string>

#include "commands/cli.h"
#include "csv/results.h"

namespace accelbench {

int convert_csv_command(int argc, char** argv) {
    const char* usage =
        "usage: accelbench convert-csv OLD NEW\n"
        "  writes the results file OLD to NEW with the renamed columns' new names (the\n"
        "  parameter columns, between params and status, keep theirs), copies OLD.reps.csv\n"
        "  beside NEW when there is one, then re-reads NEW and checks that every row and value\n"
        "  is OLD's. Renames:";
    if (argc == 1 && (std::string(argv[0]) == "-h" || std::string(argv[0]) == "--help")) {
        std::printf("%s", usage);
        for (const RenamedColumn& r : renamed_columns()) std::printf(" %s -> %s", r.old_name, r.new_name);
        std::printf("\n");
        return 0;
    }
    if (argc != 2) {
        std::fprintf(stderr, "accelbench convert-csv: takes OLD and NEW\n%s (see --help)\n", usage);
        return 2;
    }
    try {
        const size_t rows = convert_results(argv[0], argv[1]);
        std::printf("%s: %zu rows converted from %s, every value checked\n", argv[1], rows, argv[0]);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench convert-csv: %s\n", e.what());
        return 1;
    }
    return 0;
}

}  // namespace accelbench
