// `accelbench columns`: the results CSV's columns, in order, as the one column table
// (csv/results.cpp) defines them: name, kind, unit and what each holds.
#include <cstdio>

#include "commands/args.h"
#include "commands/cli.h"
#include "csv/results.h"

namespace accelbench {

int columns_command(int argc, char** argv) {
    Args args("columns",
              "usage: accelbench columns\n"
              "  prints the results CSV's columns in file order, tab-separated: name, kind\n"
              "  (text, number or parameter), unit (- for none) and what the column holds\n",
              argc, argv);
    if (auto code = args.walk([&] { args.unknown(); })) return *code;
    std::printf("name\tkind\tunit\ttext\n");
    for (const ColumnSpec& c : result_column_table())
        std::printf("%s\t%s\t%s\t%s\n", c.name.c_str(), column_kind_name(c.kind), c.unit.empty() ? "-" : c.unit.c_str(),
                    c.text.c_str());
    return 0;
}

}  // namespace accelbench
