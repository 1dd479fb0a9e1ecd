// What a results file was measured from besides the code: the config's bytes, each model
// file's and each ray file's, as sha256. A run writes them beside its results file
// (NAME.inputs.csv beside NAME.csv) before it measures; --resume and merge compare them, so
// that rows measured from other contents under the same names (a config edited, a mesh
// file replaced) are never put in one file. The code is the provenance columns' part.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace accelbench {

struct RunInput {
    std::string kind;    // "config", "model", "rays" or "reader" (a model file another library reads)
    std::string sha256;  // config, mesh or ray file: the file's; registry model: its entry's; reader: of its name
    std::string name;  // config: its name; model: its label; rays: the file as written; reader: "LABEL read by READER"
    bool operator==(const RunInput&) const = default;
};
using RunInputs = std::vector<RunInput>;

// "<results minus .csv>.inputs.csv"
std::string inputs_path(const std::string& results_path);

// The record of `results_path`'s inputs; nullopt when there is none (a file written before
// records existed, or not by a run). Throws std::runtime_error for a malformed record.
std::optional<RunInputs> read_inputs(const std::string& results_path);
// Throws std::runtime_error naming it when the record's path is taken by something that is
// not a regular file (a directory, a FIFO): checked before anything is written or measured.
void require_inputs_path_free(const std::string& results_path);
// Writes the record through a temporary file.
void write_inputs(const std::string& results_path, const RunInputs& inputs);
void remove_inputs(const std::string& results_path);

// Where two records differ, one "; "-separated item per input ("model m.obj: sha256
// 1a2b3c4d5e6f in A, 9f8e7d6c5b4a in B", "config e2e: only in B"); "" when they are equal
// (order does not matter).
std::string inputs_differences(const RunInputs& a, const std::string& a_name, const RunInputs& b,
                               const std::string& b_name);

}  // namespace accelbench
