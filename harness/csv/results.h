// The results CSV: its columns (one list, so a later column is one line), the appending
// writer, what --resume needs from an existing file, and merging shard files.
#pragma once

#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "csv/csv.h"

namespace accelbench {

using Row = std::map<std::string, std::string>;

// Columns are named by keys. A parameter's column has the key "param:<name>" and the
// header text <name>: the CSV's documented layout (docs/configs.md, analysis/README.md)
// puts one column per parameter name between `params` and `status`. Every header text
// is in the file once (check_column_names), so pandas, csv.DictReader, R and spreadsheets
// read every column by its name.
std::string param_column(const std::string& param);
// The header text of a column key.
std::string column_header(const std::string& key);
std::vector<std::string> column_headers(const std::vector<std::string>& keys);

// What a column holds. Merge refuses a Number cell that is neither empty (not measured)
// nor a finite number; a Parameter cell holds the value given in the config.
enum class ColumnKind { Text, Number, Parameter };
const char* column_kind_name(ColumnKind kind);  // "text", "number", "parameter"

// One column of the results CSV: its header text, kind, unit ("" for none) and what it is.
struct ColumnSpec {
    std::string name;
    ColumnKind kind = ColumnKind::Text;
    std::string unit;
    std::string text;
    std::string key() const { return kind == ColumnKind::Parameter ? param_column(name) : name; }
};

// The results CSV's columns in order: identification, one column per parameter name of
// every accelerator in the registry (so the header is the same for every config), status,
// timing statistics, counters, render settings and provenance. The one definition of the
// columns: result_columns, merge's number checks and `accelbench columns` read it.
std::vector<ColumnSpec> result_column_table();

// Throws std::logic_error naming every header text that `table` holds more than once (a
// parameter named like a measured column, say): the harness refuses to start with one.
void check_column_names(const std::vector<ColumnSpec>& table);

// The keys of result_column_table(), in order.
std::vector<std::string> result_columns();

// A measured or global column renamed so that no header text repeats: the old name was
// also a parameter's (max_depth, width, threads) or went with one (height).
struct RenamedColumn {
    const char* old_name;
    const char* new_name;
};
const std::vector<RenamedColumn>& renamed_columns();

// Whether `header` is a results header from before the renames (an old name after
// `status`, where only measured and global columns are), before the label column, or
// before the added columns fp_mode (after shading), embree_isa (after isa), the plugin's
// and compile_flags (after build_type).
bool is_old_results_header(const std::vector<std::string>& header);
// For an old header: "<path>: written before ... renamed: max_depth -> tree_depth, ...;
// convert it with `accelbench convert-csv <path> NEW`". Empty for any other header.
std::string old_header_message(const std::string& path, const std::vector<std::string>& header);

// `old_csv` rewritten to `new_csv` with the renamed columns' new names, every value kept,
// and its .reps.csv (unchanged: no renamed column) copied beside when there is one. A
// missing label gets the registry's; a missing fp_mode "ieee" (older rows traced in IEEE
// mode), a missing embree_isa or compile_flags "unknown". Then checks `new_csv`: re-read, same header but
// the renames and added columns, same rows, every value equal.
// Throws std::runtime_error for a file that is not an old results file (a current one
// included) or a failed check. Returns the row count.
size_t convert_results(const std::string& old_csv, const std::string& new_csv);

// One row per counted repetition (<results>.reps.csv).
std::vector<std::string> repetition_columns();

// The provenance columns that must agree for rows to be compared or merged.
const std::vector<std::string>& provenance_columns();

// The endings of a results file's companions (".reps.csv", ".inputs.csv"): the files beside
// it that readers of a results folder skip. The one list of them.
const std::vector<std::string>& companion_suffixes();
// Throws std::runtime_error for a results file name that ends like a companion: written,
// it would never be read back as results. Every writer of a results file calls it first.
void require_results_name(const std::string& path);

// The one rule for mixing (provenance.h's mixing_columns): throws std::runtime_error naming
// the column and each value with its file unless every row of every `data` agrees on each
// (names[i] names data[i]). merge, --take-column and run --resume call it; --allow-mixed
// skips it in each.
void check_same_build(const std::vector<CsvData>& data, const std::vector<std::string>& names);
// One row of this process's provenance columns, for check_same_build against a file.
CsvData this_build_rows();

// "<results minus .csv>.reps.csv"
std::string repetitions_path(const std::string& results_path);

// Appends rows to a CSV file, writing the header first when the file is new or empty;
// an existing file must have exactly the headers of `columns` (keys) as its header. Each row is written and
// flushed at once, so an interrupted run keeps every finished row.
class CsvAppender {
public:
    CsvAppender(const std::string& path, std::vector<std::string> columns);
    // Throws std::logic_error for a key that is not a column (a misspelt column must not
    // silently vanish); missing keys are written empty.
    void append(const Row& row);
    const std::string& path() const { return path_; }

private:
    std::string path_;
    std::vector<std::string> columns_;
    std::ofstream out_;
};

// For --resume: the combo_ids already in the results file. Cuts a last line left without
// its newline by a killed run, checks the header, and drops repetition rows of combinations
// that have no results row (their results row was never written, so they run again).
// Throws std::runtime_error when the existing header differs from the headers of
// `columns` (keys).
std::set<std::string> prepare_resume(const std::string& results_path, const std::vector<std::string>& columns,
                                     const std::vector<std::string>& rep_columns);

// Joins result files (and their .reps.csv files when every input has one) into `out`.
// Refuses, with std::runtime_error naming the column and values: different headers, the
// same combo_id twice, and mixed provenance unless allow_mixed. Returns the row count.
size_t merge_results(const std::string& out, const std::vector<std::string>& inputs, bool allow_mixed);

// The columns --take-column may take (instructions): counted in a run of their own, they
// leave no other column of the row contradicting them.
const std::vector<std::string>& takeable_columns();

// Writes `in` to `out` (and its .reps.csv beside, when there is one) with `column` taken
// from `from`, matched by combo_id: e.g. the instructions of a callgrind run added to a
// timed run of the same config. Rows of `in` without a match in `from` keep their value.
// Refuses, with std::runtime_error: a column not in takeable_columns(), OUT equal to IN or
// FROM, a cut last row in either, a value that is no number, different headers, mixed
// builds (check_same_build, unless allow_mixed) and a combo_id twice in `from`. Returns the
// number of rows that took a value.
size_t take_column(const std::string& out, const std::string& in, const std::string& from, const std::string& column,
                   bool allow_mixed);

}  // namespace accelbench
