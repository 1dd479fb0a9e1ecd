#include "csv/run_inputs.h"

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>

#include "csv/csv.h"
#include "util/output_lock.h"
#include "util/text.h"

namespace fs = std::filesystem;

namespace accelbench {

namespace {

const std::vector<std::string> kHeader = {"kind", "sha256", "name"};

std::string short_sha(const std::string& sha) { return sha.substr(0, 12); }

}  // namespace

std::string inputs_path(const std::string& results_path) {
    fs::path p(results_path);
    if (p.extension() == ".csv") p.replace_extension();
    return p.string() + ".inputs.csv";
}

std::optional<RunInputs> read_inputs(const std::string& results_path) {
    const std::string path = inputs_path(results_path);
    if (!fs::exists(path)) return std::nullopt;
    const CsvData d = read_csv(path);
    if (d.header != kHeader || d.incomplete_tail)
        throw std::runtime_error(path + ": not a record of a run's inputs (expected the columns kind,sha256,name)");
    RunInputs inputs;
    for (const auto& r : d.rows) inputs.push_back({r[0], r[1], r[2]});
    return inputs;
}

void require_inputs_path_free(const std::string& results_path) {
    require_regular_file_or_absent(inputs_path(results_path), "the record of inputs beside '" + results_path + "'");
}

void write_inputs(const std::string& results_path, const RunInputs& inputs) {
    require_inputs_path_free(results_path);
    const std::string path = inputs_path(results_path), tmp = path + ".tmp";
    if (!fs::path(path).parent_path().empty()) fs::create_directories(fs::path(path).parent_path());
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out << csv_line(kHeader);
        for (const RunInput& i : inputs) out << csv_line({i.kind, i.sha256, i.name});
        if (!out.flush()) throw std::runtime_error("writing '" + tmp + "' failed");
    }
    fs::rename(tmp, path);
}

void remove_inputs(const std::string& results_path) {
    require_inputs_path_free(results_path);
    fs::remove(inputs_path(results_path));
}

std::string inputs_differences(const RunInputs& a, const std::string& a_name, const RunInputs& b,
                               const std::string& b_name) {
    // kind and name -> the sha256s each side records under them
    std::map<std::pair<std::string, std::string>, std::pair<std::set<std::string>, std::set<std::string>>> by_name;
    for (const RunInput& i : a) by_name[{i.kind, i.name}].first.insert(i.sha256);
    for (const RunInput& i : b) by_name[{i.kind, i.name}].second.insert(i.sha256);
    auto shas = [](const std::set<std::string>& s) {
        std::string out;
        for (const auto& sha : s) append_item(out, "/", short_sha(sha));
        return out;
    };
    std::string out;
    for (const auto& [key, sides] : by_name) {
        const auto& [in_a, in_b] = sides;
        if (in_a == in_b) continue;
        const std::string what = key.first + " " + key.second + ": ";
        if (in_a.empty()) append_item(out, "; ", what, "only in ", b_name);
        else if (in_b.empty()) append_item(out, "; ", what, "only in ", a_name);
        else append_item(out, "; ", what, "sha256 ", shas(in_a), " in ", a_name, ", ", shas(in_b), " in ", b_name);
    }
    return out;
}

}  // namespace accelbench
