#include "sinks/verdict_table.h"

#include <algorithm>
#include <map>

#include "util/text.h"

namespace accelbench {

void VerdictTable::report(const CombinationResult& result) {
    if (result.written() && result.model.kind == ModelSpec::Kind::Case)
        add(result.model.label, result.combination, result.measurement);
}

void VerdictTable::finalize() {
    if (empty()) return;
    std::fflush(stdout);
    print(out_);
}

namespace {

size_t index_of(std::vector<std::string>& list, const std::string& item) {
    auto it = std::find(list.begin(), list.end(), item);
    if (it != list.end()) return size_t(it - list.begin());
    list.push_back(item);
    return list.size() - 1;
}

}  // namespace

void VerdictTable::add(const std::string& case_label, const Combination& c, const Measurement& m) {
    std::string accel = c.accel, given;
    for (const auto& [k, v] : c.given) append_item(given, ",", k, "=", v);
    if (!given.empty()) accel += ":" + given;
    Cell cell{index_of(rows_, case_label), index_of(columns_, accel), "", ""};
    auto verdict = m.columns.find("verdict");
    if (m.status == "ok" && verdict != m.columns.end()) {
        cell.text = verdict->second == "pass" ? "pass" : "FAIL";
        if (cell.text == "FAIL")
            cell.details = concat(m.columns.at("verdict_counts"), m.message.empty() ? "" : ": ", m.message);
    } else {
        cell.text = m.status == "timeout" ? "t/o" : m.status == "skipped" ? "skip" : "err";
        if (m.status != "skipped") cell.details = concat(m.status, ": ", m.message);
    }
    cells_.push_back(std::move(cell));
}

void VerdictTable::print(std::FILE* out) const {
    std::fprintf(out, "\nRobustness verdicts (requirements in core/accelbench/verify/robustness_cases.h):\n");
    for (size_t j = 0; j < columns_.size(); ++j) std::fprintf(out, "  [%zu] %s\n", j + 1, columns_[j].c_str());
    size_t label_width = 4;
    for (const auto& r : rows_) label_width = std::max(label_width, r.size());
    std::vector<std::vector<std::string>> grid(rows_.size(), std::vector<std::string>(columns_.size()));
    for (const auto& c : cells_) grid[c.row][c.column] = c.text;
    std::fprintf(out, "%-*s", int(label_width), "case");
    for (size_t j = 0; j < columns_.size(); ++j)
        std::fprintf(out, " %5s", concat("[", std::to_string(j + 1), "]").c_str());
    std::fprintf(out, "\n");
    std::map<std::string, size_t> totals;
    for (size_t i = 0; i < rows_.size(); ++i) {
        std::fprintf(out, "%-*s", int(label_width), rows_[i].c_str());
        for (size_t j = 0; j < columns_.size(); ++j) {
            std::fprintf(out, " %5s", grid[i][j].c_str());
            if (!grid[i][j].empty()) ++totals[grid[i][j]];
        }
        std::fprintf(out, "\n");
    }
    std::string summary;
    for (const auto& [text, n] : totals) append_item(summary, ", ", std::to_string(n), " ", text);
    std::fprintf(out, "%s\n", summary.c_str());
    bool header = false;
    for (const auto& c : cells_) {
        if (c.details.empty()) continue;
        if (!header) std::fprintf(out, "Failures:\n");
        header = true;
        std::fprintf(out, "  %s x [%zu] %s: %s %s\n", rows_[c.row].c_str(), c.column + 1, columns_[c.column].c_str(),
                     c.text.c_str(), c.details.c_str());
    }
}

}  // namespace accelbench
