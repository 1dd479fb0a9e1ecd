#include "csv/results.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <stdexcept>

#include "accelbench/accel/registry.h"
#include "csv/csv.h"
#include "util/output_lock.h"

namespace fs = std::filesystem;

namespace accelbench {

namespace {
const std::string kParamKey = "param:";

// The columns after the parameters, in order, and what each holds: merge refuses a row
// whose Number column is neither empty (not measured) nor a finite number.
enum class ColumnKind { Text, Number };
struct MeasuredColumn {
    const char* name;
    ColumnKind kind;
};
const MeasuredColumn kMeasuredColumns[] = {
    {"status", ColumnKind::Text},
    {"message", ColumnKind::Text},
    {"repetitions", ColumnKind::Number},
    {"build_s_median", ColumnKind::Number},
    {"build_s_mean", ColumnKind::Number},
    {"build_s_stddev", ColumnKind::Number},
    {"build_s_ci_lo", ColumnKind::Number},
    {"build_s_ci_hi", ColumnKind::Number},
    {"render_s_median", ColumnKind::Number},
    {"render_s_mean", ColumnKind::Number},
    {"render_s_stddev", ColumnKind::Number},
    {"render_s_ci_lo", ColumnKind::Number},
    {"render_s_ci_hi", ColumnKind::Number},
    {"ci_coverage", ColumnKind::Number},
    {"render_cpu_s_median", ColumnKind::Number},
    {"rays", ColumnKind::Number},
    {"hits", ColumnKind::Number},
    {"shadow_rays", ColumnKind::Number},
    {"shadow_hits", ColumnKind::Number},
    {"mrays_per_s", ColumnKind::Number},
    {"nodes", ColumnKind::Number},
    {"leaves", ColumnKind::Number},
    {"max_depth", ColumnKind::Number},
    {"memory_bytes", ColumnKind::Number},
    {"sah_cost", ColumnKind::Number},
    {"avg_leaf_size", ColumnKind::Number},
    {"build_extra", ColumnKind::Text},
    {"prim_tests", ColumnKind::Number},
    {"node_visits", ColumnKind::Number},
    {"box_tests", ColumnKind::Number},
    {"prim_tests_per_ray", ColumnKind::Number},
    {"node_visits_per_ray", ColumnKind::Number},
    {"instructions", ColumnKind::Number},
    {"false_misses", ColumnKind::Number},
    {"false_hits", ColumnKind::Number},
    {"prim_mismatches", ColumnKind::Number},
    {"t_err_ulp_p50", ColumnKind::Number},
    {"t_err_ulp_max", ColumnKind::Number},
    {"nan_results", ColumnKind::Number},
    {"image_rmse", ColumnKind::Number},
    {"hole_pixels", ColumnKind::Number},
    {"peak_rss_bytes", ColumnKind::Number},
    {"verdict", ColumnKind::Text},
    {"verdict_counts", ColumnKind::Text},
    {"width", ColumnKind::Number},
    {"height", ColumnKind::Number},
    {"spp", ColumnKind::Number},
    {"light", ColumnKind::Text},
    {"shading", ColumnKind::Text},
    {"git_sha", ColumnKind::Text},
    {"git_dirty", ColumnKind::Text},
    {"compiler", ColumnKind::Text},
    {"build_type", ColumnKind::Text},
    {"cpu", ColumnKind::Text},
    {"threads", ColumnKind::Text},
    {"embree_version", ColumnKind::Text},
    {"timestamp", ColumnKind::Text},
    {"isa", ColumnKind::Text},
};
}  // namespace

std::string param_column(const std::string& param) { return kParamKey + param; }

std::string column_header(const std::string& key) {
    return key.rfind(kParamKey, 0) == 0 ? key.substr(kParamKey.size()) : key;
}

std::vector<std::string> column_headers(const std::vector<std::string>& keys) {
    std::vector<std::string> h;
    for (const auto& k : keys) h.push_back(column_header(k));
    return h;
}

std::vector<std::string> result_columns() {
    std::vector<std::string> c = {"config",     "combo_id", "model",        "triangles", "vertices",
                                  "ray_source", "ray_set",  "ray_set_hash", "accel",     "params"};
    // Every accelerator's parameters, in registry then declaration order, each once.
    std::set<std::string> seen;
    for (const auto& info : accelerator_registry())
        for (const auto& p : info.params)
            if (seen.insert(p.name).second) c.push_back(param_column(p.name));
    for (const MeasuredColumn& col : kMeasuredColumns) c.push_back(col.name);
    return c;
}

std::vector<std::string> repetition_columns() {
    return {"config", "combo_id", "model", "accel", "params", "repetition", "build_s", "render_s"};
}

const std::vector<std::string>& provenance_columns() {
    static const std::vector<std::string> cols = {"git_sha", "git_dirty",      "compiler", "build_type",
                                                  "cpu",     "embree_version", "isa"};
    return cols;
}

std::string repetitions_path(const std::string& results_path) {
    fs::path p(results_path);
    if (p.extension() == ".csv") p.replace_extension();
    return p.string() + ".reps.csv";
}

namespace {

std::string header_mismatch(const std::string& path, const std::vector<std::string>& have,
                            const std::vector<std::string>& want) {
    for (size_t i = 0; i < std::max(have.size(), want.size()); ++i) {
        const std::string a = i < have.size() ? have[i] : "(none)";
        const std::string b = i < want.size() ? want[i] : "(none)";
        if (a != b)
            return path + ": its columns differ from this build's (column " + std::to_string(i + 1) + " is '" + a +
                "', expected '" + b + "'); write to a new file or merge with an older build's binary";
    }
    return "";
}

}  // namespace

CsvAppender::CsvAppender(const std::string& path, std::vector<std::string> columns)
    : path_(path), columns_(std::move(columns)) {
    const bool fresh = !fs::exists(path) || fs::file_size(path) == 0;
    if (!fresh) {
        CsvData existing = read_csv(path);
        if (auto m = header_mismatch(path, existing.header, column_headers(columns_)); !m.empty())
            throw std::runtime_error(m);
        if (existing.incomplete_tail) fs::resize_file(path, existing.complete_bytes);
    }
    if (!fs::path(path).parent_path().empty()) fs::create_directories(fs::path(path).parent_path());
    out_.open(path, std::ios::app | std::ios::binary);
    if (!out_) throw std::runtime_error("cannot open '" + path + "' for writing");
    if (fresh) {
        out_ << csv_line(column_headers(columns_));
        out_.flush();
    }
}

void CsvAppender::append(const Row& row) {
    std::vector<std::string> fields;
    fields.reserve(columns_.size());
    for (const auto& c : columns_) {
        auto it = row.find(c);
        fields.push_back(it == row.end() ? "" : it->second);
    }
    for (const auto& [k, v] : row)
        if (std::find(columns_.begin(), columns_.end(), k) == columns_.end())
            throw std::logic_error("row has a value for '" + k + "', which is not a column of " + path_);
    out_ << csv_line(fields);
    out_.flush();
    if (!out_) throw std::runtime_error("writing to '" + path_ + "' failed");
}

namespace {

size_t column_index(const CsvData& d, const std::string& name, const std::string& path) {
    for (size_t i = 0; i < d.header.size(); ++i)
        if (d.header[i] == name) return i;
    throw std::runtime_error(path + ": no column '" + name + "'");
}

// Rewrites `path` keeping the rows whose combo_id is in `keep`.
void filter_rows(const std::string& path, const std::set<std::string>& keep) {
    CsvData d = read_csv(path);
    const size_t id = column_index(d, "combo_id", path);
    const std::string tmp = path + ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out << csv_line(d.header);
        for (const auto& r : d.rows)
            if (keep.count(r[id])) out << csv_line(r);
        if (!out.flush()) throw std::runtime_error("writing '" + tmp + "' failed");
    }
    fs::rename(tmp, path);
}

// Refuses files from different builds or machines: their rows are not comparable.
void check_same_provenance(const std::vector<CsvData>& data, const std::vector<std::string>& paths) {
    for (const auto& col : provenance_columns()) {
        const size_t c = column_index(data.front(), col, paths.front());
        std::map<std::string, std::string> seen;  // value -> first file with it
        for (size_t f = 0; f < data.size(); ++f)
            for (const auto& r : data[f].rows) seen.emplace(r[c], paths[f]);
        if (seen.size() > 1) {
            std::string values;
            for (const auto& [v, file] : seen) values += "\n  '" + v + "' (" + file + ")";
            throw std::runtime_error("mixed provenance: column " + col + " differs between the inputs:" + values +
                                     "\nresults from different builds or machines are not comparable; "
                                     "pass --allow-mixed to merge them anyway");
        }
    }
}

// Writes the parts' rows under the first part's header, through a temporary file.
void write_parts(const std::string& path, const std::vector<CsvData>& parts) {
    if (!fs::path(path).parent_path().empty()) fs::create_directories(fs::path(path).parent_path());
    const std::string tmp = path + ".tmp";
    {
        std::ofstream o(tmp, std::ios::binary | std::ios::trunc);
        if (!o) throw std::runtime_error("cannot write '" + tmp + "'");
        o << csv_line(parts.front().header);
        for (const auto& p : parts)
            for (const auto& r : p.rows) o << csv_line(r);
        if (!o.flush()) throw std::runtime_error("writing '" + tmp + "' failed");
    }
    fs::rename(tmp, path);
}

}  // namespace

std::set<std::string> prepare_resume(const std::string& results_path, const std::vector<std::string>& columns,
                                     const std::vector<std::string>& rep_columns) {
    std::set<std::string> done;
    if (fs::exists(results_path) && fs::file_size(results_path) > 0) {
        CsvData d = read_csv(results_path);
        if (auto m = header_mismatch(results_path, d.header, column_headers(columns)); !m.empty())
            throw std::runtime_error(m);
        if (d.incomplete_tail) fs::resize_file(results_path, d.complete_bytes);
        const size_t id = column_index(d, "combo_id", results_path);
        for (const auto& r : d.rows) done.insert(r[id]);
    }
    // Also when the results file is gone or empty: then every repetition row is an orphan
    // and is dropped, so samples of two runs are never mixed.
    const std::string reps = repetitions_path(results_path);
    if (fs::exists(reps) && fs::file_size(reps) > 0) {
        CsvData rd = read_csv(reps);
        if (auto m = header_mismatch(reps, rd.header, column_headers(rep_columns)); !m.empty())
            throw std::runtime_error(m);
        filter_rows(reps, done);
    }
    return done;
}

namespace {

// A results file's rows as merge accepts them: a combo_id, a known status, numbers where
// the columns hold numbers (empty: not measured). `path` and the row (1 = the first after
// the header) name each refusal.
void check_result_rows(const CsvData& d, const std::string& path) {
    static const std::set<std::string> statuses = {"ok", "skipped", "error", "timeout"};
    static const std::set<std::string> numeric = [] {
        std::set<std::string> n = {"triangles", "vertices"};
        for (const MeasuredColumn& col : kMeasuredColumns)
            if (col.kind == ColumnKind::Number) n.insert(col.name);
        return n;
    }();
    const size_t id = column_index(d, "combo_id", path);
    auto optional_column = [&](const char* name) {
        const auto it = std::find(d.header.begin(), d.header.end(), name);
        return it == d.header.end() ? std::optional<size_t>() : size_t(it - d.header.begin());
    };
    const std::optional<size_t> status = optional_column("status"), params = optional_column("params");
    // Parameter columns (between params and status) may share a name with a measured
    // column (max_depth): only the measured one is checked here.
    std::vector<size_t> checked;
    for (size_t c = 0; c < d.header.size(); ++c)
        if (!(params && status && c > *params && c < *status) && numeric.count(d.header[c])) checked.push_back(c);
    for (size_t i = 0; i < d.rows.size(); ++i) {
        const auto& r = d.rows[i];
        const std::string where = path + ", row " + std::to_string(i + 1);
        if (r[id].empty()) throw std::runtime_error(where + ": empty combo_id");
        if (status && !statuses.count(r[*status]))
            throw std::runtime_error(where + ": unknown status '" + r[*status] + "' (ok, skipped, error or timeout)");
        for (size_t c : checked) {
            const std::string& v = r[c];
            if (v.empty()) continue;
            char* end = nullptr;
            const double x = std::strtod(v.c_str(), &end);
            if (std::isspace(static_cast<unsigned char>(v.front())) || end != v.c_str() + v.size() || !std::isfinite(x))
                throw std::runtime_error(where + ", column " + d.header[c] + ": '" + v + "' is not a finite number");
        }
    }
}

// Every repetition row belongs to a results row of its own input.
void check_no_orphans(const CsvData& results, const std::string& results_path, const CsvData& reps,
                      const std::string& reps_path) {
    std::set<std::string> ids;
    const size_t id = column_index(results, "combo_id", results_path);
    for (const auto& r : results.rows) ids.insert(r[id]);
    const size_t rid = column_index(reps, "combo_id", reps_path);
    for (size_t i = 0; i < reps.rows.size(); ++i)
        if (!ids.count(reps.rows[i][rid]))
            throw std::runtime_error(reps_path + ", row " + std::to_string(i + 1) + ": repetition of combination '" +
                                     reps.rows[i][rid] + "', which has no row in " + results_path);
}

// What merge and take_column write: OUT.reps.csv first, then OUT (as a run writes a
// combination's repetitions before its row), both under OUT's locks; without repetitions
// an OUT.reps.csv left from an earlier file is removed, never left beside the new OUT.
void write_output(const std::string& out, const std::vector<CsvData>& results, const std::vector<CsvData>* reps) {
    const std::string reps_out = repetitions_path(out);
    OutputLock lock({out, reps_out});
    if (reps) write_parts(reps_out, *reps);
    else fs::remove(reps_out);
    write_parts(out, results);
}

}  // namespace

size_t merge_results(const std::string& out, const std::vector<std::string>& inputs, bool allow_mixed) {
    if (inputs.empty()) throw std::runtime_error("nothing to merge");
    for (const auto& in : inputs)
        if (fs::exists(out) && fs::exists(in) && fs::equivalent(out, in))
            throw std::runtime_error("the output '" + out + "' is also an input");
    std::vector<CsvData> data;
    for (const auto& in : inputs) {
        data.push_back(read_csv(in));
        if (data.back().incomplete_tail)
            throw std::runtime_error(in + ": the last line is incomplete (an interrupted run?); resume it first");
        if (auto m = header_mismatch(in, data.back().header, data.front().header); !m.empty())
            throw std::runtime_error(m + " (compared with " + inputs.front() + ")");
        check_result_rows(data.back(), in);
    }
    const CsvData& first = data.front();
    const size_t id = column_index(first, "combo_id", inputs.front());
    if (!allow_mixed) check_same_provenance(data, inputs);
    std::map<std::string, std::string> owner;  // combo_id -> file
    for (size_t f = 0; f < data.size(); ++f)
        for (const auto& r : data[f].rows)
            if (auto [it, fresh] = owner.emplace(r[id], inputs[f]); !fresh)
                throw std::runtime_error("combination " + r[id] + " is in both " + it->second + " and " + inputs[f] +
                                         " (overlapping shards?)");

    bool all_reps = true;
    for (const auto& in : inputs) all_reps &= fs::exists(repetitions_path(in));
    std::vector<CsvData> reps;
    if (all_reps)
        for (const auto& in : inputs) {
            reps.push_back(read_csv(repetitions_path(in)));
            if (auto m = header_mismatch(repetitions_path(in), reps.back().header, reps.front().header); !m.empty())
                throw std::runtime_error(m);
            check_no_orphans(data[reps.size() - 1], in, reps.back(), repetitions_path(in));
        }

    write_output(out, data, all_reps ? &reps : nullptr);
    return owner.size();
}

size_t take_column(const std::string& out, const std::string& in, const std::string& from, const std::string& column,
                   bool allow_mixed) {
    if (fs::exists(out) && fs::exists(in) && fs::equivalent(out, in))
        throw std::runtime_error("the output '" + out + "' is also an input");
    std::vector<CsvData> data = {read_csv(in), read_csv(from)};
    if (auto m = header_mismatch(from, data[1].header, data[0].header); !m.empty())
        throw std::runtime_error(m + " (compared with " + in + ")");
    if (!allow_mixed) check_same_provenance(data, {in, from});
    const size_t id = column_index(data[0], "combo_id", in), col = column_index(data[0], column, in);
    std::map<std::string, std::string> value;  // combo_id -> the column's value in `from`
    for (const auto& r : data[1].rows)
        if (!value.emplace(r[id], r[col]).second)
            throw std::runtime_error("combination " + r[id] + " is in " + from + " twice");
    size_t taken = 0;
    for (auto& r : data[0].rows)
        if (auto it = value.find(r[id]); it != value.end() && !it->second.empty()) {
            r[col] = it->second;
            ++taken;
        }
    std::vector<CsvData> reps;
    if (fs::exists(repetitions_path(in))) reps.push_back(read_csv(repetitions_path(in)));
    write_output(out, {data[0]}, reps.empty() ? nullptr : &reps);
    return taken;
}

}  // namespace accelbench
