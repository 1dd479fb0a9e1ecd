// The results CSV: its columns (one list, so a later column is one line), the appending
// writer, what --resume needs from an existing file, and merging shard files.
#pragma once

#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace accelbench {

using Row = std::map<std::string, std::string>;

// Columns are named by keys. A parameter's column has the key "param:<name>" and the
// header text <name>: the CSV's documented layout (docs/configs.md, analysis/README.md)
// puts one column per parameter name between `params` and `status`, so a parameter may
// share its header text with a measured column (`max_depth`, the limit vs the depth
// reached) or provenance (`threads`); readers tell them apart by position, the harness by
// key.
std::string param_column(const std::string& param);
// The header text of a column key.
std::string column_header(const std::string& key);
std::vector<std::string> column_headers(const std::vector<std::string>& keys);

// One row per combination: identification, one column per parameter name of every
// accelerator in the registry (so the header is the same for every config), status,
// timing statistics, counters, render settings and provenance. Keys, in order.
std::vector<std::string> result_columns();

// One row per counted repetition (<results>.reps.csv).
std::vector<std::string> repetition_columns();

// The provenance columns that must agree for rows to be compared or merged.
const std::vector<std::string>& provenance_columns();

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

// Writes `in` to `out` (and its .reps.csv beside, when there is one) with `column` taken
// from `from`, matched by combo_id: e.g. the instructions of a callgrind run added to a
// timed run of the same config. Rows of `in` without a match in `from` keep their value.
// Refuses, with std::runtime_error: different headers, a column that is not in them,
// mixed provenance (unless allow_mixed) and a combo_id twice in `from`. Returns the
// number of rows that took a value.
size_t take_column(const std::string& out, const std::string& in, const std::string& from, const std::string& column,
                   bool allow_mixed);

}  // namespace accelbench
