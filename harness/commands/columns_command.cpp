// `accelbench columns`: the results CSV's columns, in order, as the one column table
// (csv/results.cpp) defines them: name, kind, unit and what each holds. --identity and
// --mixing print the provenance lists (csv/provenance.h), one name a line, so that the
// analysis's copies of them (inputs/provenance.py) are checked against the harness's.
#include <cstdio>
#include <string>
#include <vector>

#include "commands/args.h"
#include "commands/cli.h"
#include "csv/provenance.h"
#include "csv/results.h"

namespace accelbench {

int columns_command(int argc, char** argv) {
    static const char* const kUsage =
        "usage: accelbench columns [--identity | --mixing]\n"
        "  prints the results CSV's columns in file order, tab-separated: name, kind\n"
        "  (text, number or parameter), unit (- for none) and what the column holds\n"
        "  --identity  only the columns that name the build that measured a row, one a line\n"
        "  --mixing    only the columns rows must agree on to share a file or a median\n"
        "              (merge, --take-column, run --resume, history): the identity and cpu\n";
    Args args("columns", kUsage, argc, argv);
    bool identity = false, mixing = false;
    if (auto code = args.walk([&] {
            if (args.flag("--identity")) identity = true;
            else if (args.flag("--mixing")) mixing = true;
            else args.unknown();
        }))
        return *code;
    if (identity && mixing) return args.error("--identity and --mixing print different lists: give one");
    if (identity || mixing) {
        for (const std::string& name : identity ? build_identity_columns() : mixing_columns())
            std::printf("%s\n", name.c_str());
        return 0;
    }
    std::printf("name\tkind\tunit\ttext\n");
    for (const ColumnSpec& c : result_column_table())
        std::printf("%s\t%s\t%s\t%s\n", c.name.c_str(), column_kind_name(c.kind), c.unit.empty() ? "-" : c.unit.c_str(),
                    c.text.c_str());
    return 0;
}

}  // namespace accelbench
