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
#include "csv/provenance.h"
#include "csv/run_inputs.h"
#include "util/output_lock.h"
#include "util/text.h"

namespace fs = std::filesystem;

namespace accelbench {

namespace {
const std::string kParamKey = "param:";

// The results CSV's columns, in order, each once: what it is called, holds and measures.
// The parameters' columns go between `params` and `status` (result_column_table). Merge
// refuses a row whose Number column is neither empty (not measured) nor a finite number.
// A column is one line here plus its value in the row (sinks/results_csv.cpp).
const ColumnSpec kIdentificationColumns[] = {
    {"config", ColumnKind::Text, "", "the config's name"},
    {"combo_id", ColumnKind::Text, "", "the combination's id, unique within a config"},
    {"model", ColumnKind::Text, "", "the model's label (registry name, path or procedural:KIND)"},
    {"triangles", ColumnKind::Number, "count", "triangles of the model"},
    {"vertices", ColumnKind::Number, "count", "vertices of the model"},
    {"ray_source", ColumnKind::Text, "", "camera, a ray file, or robustness-case"},
    {"ray_set", ColumnKind::Text, "", "the timed ray set (camera: primary + shadow rays)"},
    {"ray_set_hash", ColumnKind::Text, "", "hash of the ray set's rays"},
    {"accel", ColumnKind::Text, "", "the structure's registry name"},
    {"label", ColumnKind::Text, "", "the structure's display label (registry), of its parameters"},
    {"params", ColumnKind::Text, "", "the parameters given, canonical k=v;k=v"},
};
const ColumnSpec kMeasuredColumns[] = {
    {"status", ColumnKind::Text, "", "ok, skipped, error or timeout"},
    {"message", ColumnKind::Text, "", "why a row is not ok"},
    {"repetitions", ColumnKind::Number, "count", "timed repetitions counted (over every measuring process)"},
    {"processes", ColumnKind::Number, "count", "child processes that measured the row, repetitions pooled"},
    {"timed_with", ColumnKind::Text, "",
     "combo_ids timed alternately with the row in the same processes (interleave), ';'-separated; empty: alone"},
    {"build_s_median", ColumnKind::Number, "s", "build time, median"},
    {"build_s_mean", ColumnKind::Number, "s", "build time, mean"},
    {"build_s_stddev", ColumnKind::Number, "s", "build time, standard deviation"},
    {"build_s_ci_lo", ColumnKind::Number, "s", "build time median, 95% CI low end"},
    {"build_s_ci_hi", ColumnKind::Number, "s", "build time median, 95% CI high end"},
    {"render_s_median", ColumnKind::Number, "s", "render time, median"},
    {"render_s_mean", ColumnKind::Number, "s", "render time, mean"},
    {"render_s_stddev", ColumnKind::Number, "s", "render time, standard deviation"},
    {"render_s_ci_lo", ColumnKind::Number, "s", "render time median, 95% CI low end"},
    {"render_s_ci_hi", ColumnKind::Number, "s", "render time median, 95% CI high end"},
    {"ci_coverage", ColumnKind::Number, "fraction", "exact coverage of the median CIs"},
    {"build_s_process_gap", ColumnKind::Number, "fraction", "build time: largest / smallest process median - 1"},
    {"render_s_process_gap", ColumnKind::Number, "fraction", "render time: largest / smallest process median - 1"},
    {"render_cpu_s_median", ColumnKind::Number, "s", "render CPU time, median"},
    {"rays", ColumnKind::Number, "count", "primary (or the set's) rays traced"},
    {"hits", ColumnKind::Number, "count", "rays that hit"},
    {"shadow_rays", ColumnKind::Number, "count", "shadow rays traced"},
    {"shadow_hits", ColumnKind::Number, "count", "shadow rays occluded"},
    {"mrays_per_s", ColumnKind::Number, "Mrays/s", "all rays / median render time"},
    {"nodes", ColumnKind::Number, "count", "nodes of the built structure"},
    {"leaves", ColumnKind::Number, "count", "leaves of the built structure"},
    {"tree_depth", ColumnKind::Number, "levels", "depth of the built tree (the measured depth)"},
    {"memory_bytes", ColumnKind::Number, "bytes", "memory of the built structure"},
    {"sah_cost", ColumnKind::Number, "", "SAH cost of the built structure"},
    {"avg_leaf_size", ColumnKind::Number, "primitives", "mean primitives per leaf"},
    {"build_extra", ColumnKind::Text, "", "structure-specific build figures, k=v;k=v"},
    {"prim_tests", ColumnKind::Number, "count", "ray/primitive tests"},
    {"node_visits", ColumnKind::Number, "count", "nodes visited"},
    {"box_tests", ColumnKind::Number, "count", "ray/box tests"},
    {"prim_tests_per_ray", ColumnKind::Number, "count", "prim_tests / all rays"},
    {"node_visits_per_ray", ColumnKind::Number, "count", "node_visits / all rays"},
    {"instructions", ColumnKind::Number, "count", "instructions of the render (callgrind Ir)"},
    {"false_misses", ColumnKind::Number, "count", "misses where the reference hits"},
    {"false_hits", ColumnKind::Number, "count", "hits where the reference misses"},
    {"prim_mismatches", ColumnKind::Number, "count", "hits on another primitive than the reference's"},
    {"t_err_ulp_p50", ColumnKind::Number, "ulp", "hit distance error vs the reference, median"},
    {"t_err_ulp_max", ColumnKind::Number, "ulp", "hit distance error vs the reference, maximum"},
    {"nan_results", ColumnKind::Number, "count", "hits with a NaN distance"},
    {"image_rmse", ColumnKind::Number, "", "RMSE of the image vs the reference's"},
    {"hole_pixels", ColumnKind::Number, "count", "pixels that miss where the reference hits"},
    {"peak_rss_bytes", ColumnKind::Number, "bytes", "peak resident memory of the measuring process"},
    {"verdict", ColumnKind::Text, "", "robustness case: pass or fail"},
    {"verdict_counts", ColumnKind::Text, "", "robustness case: the counts behind the verdict"},
    {"image_width", ColumnKind::Number, "pixels", "rendered image width"},
    {"image_height", ColumnKind::Number, "pixels", "rendered image height"},
    {"spp", ColumnKind::Number, "count", "samples per pixel"},
    {"light", ColumnKind::Text, "", "shadow rays to the light: true or false"},
    {"shading", ColumnKind::Text, "", "shading on: true or false"},
    {"fp_mode", ColumnKind::Text, "", "floating-point mode of every trace: ieee or ftz_daz (robustness cases: ieee)"},
    {"git_sha", ColumnKind::Text, "", "provenance: the commit built"},
    {"git_dirty", ColumnKind::Text, "", "provenance: code differs from the commit"},
    {"compiler", ColumnKind::Text, "", "provenance: compiler and version"},
    {"build_type", ColumnKind::Text, "", "provenance: CMake build type"},
    {"compile_flags", ColumnKind::Text, "",
     "provenance: compiler flags that change the code (CMake's, the build type's, -march)"},
    {"cpu", ColumnKind::Text, "", "provenance: CPU model"},
    {"render_threads", ColumnKind::Number, "count", "threads the render ran on"},
    {"embree_version", ColumnKind::Text, "", "provenance: Embree version"},
    {"timestamp", ColumnKind::Text, "", "when the row was measured (UTC)"},
    {"isa", ColumnKind::Text, "", "provenance: vector extensions compiled in"},
    {"embree_isa", ColumnKind::Text, "",
     "provenance: instruction set of the kernels Embree runs (its run-time choice)"},
    {"plugin_file", ColumnKind::Text, "", "provenance: the plugin's shared library (empty: compiled in)"},
    {"plugin_sha256", ColumnKind::Text, "", "provenance: SHA-256 of the plugin's file"},
    {"plugin_version", ColumnKind::Text, "", "provenance: the plugin's own version string"},
};

// Measured and global columns that once had the name of a parameter (the limit and the
// depth reached, the wide BVH's width and the image's, the build's threads and the
// render's); the old header had both names, the parameter's between params and status.
const RenamedColumn kRenamedColumns[] = {
    {"max_depth", "tree_depth"},
    {"width", "image_width"},
    {"height", "image_height"},
    {"threads", "render_threads"},
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

const char* column_kind_name(ColumnKind kind) {
    switch (kind) {
        case ColumnKind::Text: return "text";
        case ColumnKind::Number: return "number";
        case ColumnKind::Parameter: return "parameter";
    }
    return "?";
}

std::vector<ColumnSpec> result_column_table() {
    std::vector<ColumnSpec> t(std::begin(kIdentificationColumns), std::end(kIdentificationColumns));
    // Every accelerator's parameters, in registry then declaration order, each once; the
    // text names the structures that have it. A plugin's parameters are in `params` only,
    // so that the header is this build's whatever plugins a run loads.
    std::map<std::string, size_t> at;  // parameter name -> its entry in t
    for (const auto& info : accelerator_registry())
        if (!info.plugin)
            for (const auto& p : info.params) {
                if (auto it = at.find(p.name); it != at.end()) {
                    std::string& text = t[it->second].text;
                    text.insert(text.find(':'), ", ").insert(text.find(':'), info.name);
                    continue;
                }
                at.emplace(p.name, t.size());
                t.push_back({p.name, ColumnKind::Parameter, "", "parameter of " + info.name + ": " + p.help});
            }
    t.insert(t.end(), std::begin(kMeasuredColumns), std::end(kMeasuredColumns));
    return t;
}

void check_column_names(const std::vector<ColumnSpec>& table) {
    std::map<std::string, std::vector<size_t>> where;  // header text -> 1-based positions
    for (size_t i = 0; i < table.size(); ++i) where[table[i].name].push_back(i + 1);
    std::string twice;
    for (const auto& [name, at] : where) {
        if (at.size() < 2) continue;
        twice.append("\n  '").append(name).append("' at columns");
        for (size_t a : at) twice.append(" ").append(std::to_string(a));
    }
    if (!twice.empty())
        throw std::logic_error(
            "the results column table holds a name more than once (a CSV reader would keep only "
            "one of them, or rename it):" +
            twice);
}

std::vector<std::string> result_columns() {
    std::vector<std::string> c;
    for (const ColumnSpec& col : result_column_table()) c.push_back(col.key());
    return c;
}

const std::vector<RenamedColumn>& renamed_columns() {
    static const std::vector<RenamedColumn> r(std::begin(kRenamedColumns), std::end(kRenamedColumns));
    return r;
}

namespace {

// The position of `status` in a results header: the columns after it are measured or
// global, those between `params` and it are parameters (the layout every version of the
// harness wrote).
std::optional<size_t> status_position(const std::vector<std::string>& header) {
    const auto it = std::find(header.begin(), header.end(), "status");
    if (it == header.end() || std::find(header.begin(), it, "params") == it) return std::nullopt;
    return size_t(it - header.begin());
}

const RenamedColumn* renamed_from(const std::string& name) {
    for (const RenamedColumn& r : renamed_columns())
        if (name == r.old_name) return &r;
    return nullptr;
}

// A results header from before the `label` column (it follows `accel`).
bool lacks_label(const std::vector<std::string>& header) {
    return std::find(header.begin(), header.end(), "accel") != header.end() &&
        std::find(header.begin(), header.end(), "label") == header.end();
}

// Columns added after files were written, each after another column, with the value every
// older row gets: before `fp_mode` the harness set no floating-point mode, so every trace
// ran in IEEE mode, the process default; which kernels Embree ran was not recorded.
struct AddedColumn {
    const char* name;
    const char* after;
    const char* old_value;
};
constexpr AddedColumn kAddedColumns[] = {
    {"fp_mode", "shading", "ieee"},
    {"embree_isa", "isa", "unknown"},
    // Plugins came later than every older row: those rows are all of structures compiled in.
    {"plugin_file", "embree_isa", ""},
    {"plugin_sha256", "plugin_file", ""},
    {"plugin_version", "plugin_sha256", ""},
    // Older rows were measured in one process each, but a skipped or failed row has no
    // measurement at all: the count is left empty (not recorded), as are the gaps.
    {"processes", "repetitions", ""},
    {"build_s_process_gap", "ci_coverage", ""},
    {"render_s_process_gap", "build_s_process_gap", ""},
    // Before `interleave` every row was timed alone in its processes.
    {"timed_with", "processes", ""},
    // Which flags compiled an older row's binary was not recorded: unknown, a build of its own.
    {"compile_flags", "build_type", "unknown"},
};

// The added columns `header` lacks (those whose predecessor it has).
std::vector<AddedColumn> missing_added_columns(const std::vector<std::string>& header) {
    std::set<std::string> have(header.begin(), header.end());  // with the columns added so far
    std::vector<AddedColumn> missing;
    for (const AddedColumn& c : kAddedColumns)
        if (have.count(c.after) && !have.count(c.name)) {
            missing.push_back(c);
            have.insert(c.name);
        }
    return missing;
}

// The registry's label of a row's structure, from its `accel` and canonical `params`; ""
// for a structure or parameter the registry no longer has. A scene-dependent default
// ("auto") is left to the structure, as a run does.
std::string registry_label(const std::string& accel, const std::string& params) {
    const AcceleratorInfo* info = find_accelerator(accel);
    if (!info) return "";
    std::map<std::string, std::string> given;
    for (size_t at = 0; at < params.size();) {
        const size_t end = std::min(params.find(';', at), params.size());
        const std::string item = params.substr(at, end - at);
        const size_t eq = item.find('=');
        if (eq != std::string::npos) given[item.substr(0, eq)] = item.substr(eq + 1);
        at = end + 1;
    }
    for (const ParamSpec& spec : info->params)
        if (spec.scene_dependent_default && given.count(spec.name) && given[spec.name] == spec.default_value)
            given.erase(spec.name);
    try {
        return info->label(resolve_params(accel, info->params, given));
    } catch (const ParamError&) {
        return "";
    }
}

}  // namespace

bool is_old_results_header(const std::vector<std::string>& header) {
    const auto status = status_position(header);
    if (!status) return false;
    if (lacks_label(header) || !missing_added_columns(header).empty()) return true;
    for (size_t i = *status + 1; i < header.size(); ++i)
        if (renamed_from(header[i])) return true;
    return false;
}

std::string old_header_message(const std::string& path, const std::vector<std::string>& header) {
    if (!is_old_results_header(header)) return "";
    std::string renames;
    for (const RenamedColumn& r : renamed_columns()) {
        if (!renames.empty()) renames.append(", ");
        renames.append(r.old_name).append(" -> ").append(r.new_name);
    }
    std::string added;
    for (const AddedColumn& c : missing_added_columns(header)) added.append(added.empty() ? "" : ", ").append(c.name);
    return path + ": written before the measured and global columns were renamed so that no name repeats (" + renames +
        "; the parameter columns keep their names)" + (lacks_label(header) ? " or before the label column" : "") +
        (added.empty() ? "" : " or before the columns " + added) + "; convert it with `accelbench convert-csv " + path +
        " NEW`";
}

std::vector<std::string> repetition_columns() {
    // `process`: the measuring process of the repetition (1-based; config key `processes`).
    return {"config", "combo_id", "model", "accel", "params", "repetition", "build_s", "render_s", "process"};
}

const std::vector<std::string>& provenance_columns() {
    static const std::vector<std::string> cols = {"git_sha",        "git_dirty",     "compiler",
                                                  "build_type",     "compile_flags", "cpu",
                                                  "embree_version", "isa",           "embree_isa"};
    return cols;
}

const std::vector<std::string>& companion_suffixes() {
    static const std::vector<std::string> suffixes = {".reps.csv", ".inputs.csv"};
    return suffixes;
}

void require_results_name(const std::string& path) {
    for (const std::string& suffix : companion_suffixes())
        if (path.size() >= suffix.size() && path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0)
            throw std::runtime_error("'" + path + "' ends in " + suffix +
                                     ", the name of a results file's companion: readers would take it for one "
                                     "and never read it as results; choose a name ending in plain .csv");
}

std::string repetitions_path(const std::string& results_path) {
    fs::path p(results_path);
    if (p.extension() == ".csv") p.replace_extension();
    return p.string() + ".reps.csv";
}

namespace {

std::string header_mismatch(const std::string& path, const std::vector<std::string>& have,
                            const std::vector<std::string>& want) {
    if (have != want && !is_old_results_header(want))
        if (auto m = old_header_message(path, have); !m.empty()) return m;
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

}  // namespace

void check_same_build(const std::vector<CsvData>& data, const std::vector<std::string>& names) {
    for (const auto& col : mixing_columns()) {
        std::map<std::string, std::string> seen;  // value -> the first file with it
        for (size_t f = 0; f < data.size(); ++f) {
            const size_t c = column_index(data[f], col, names[f]);
            for (const auto& r : data[f].rows) seen.emplace(r[c], names[f]);
        }
        if (seen.size() > 1) {
            std::string values;
            for (const auto& [v, file] : seen) values += "\n  '" + v + "' (" + file + ")";
            throw std::runtime_error("mixed builds: column " + col + " differs:" + values +
                                     "\nrows of different builds or machines are not comparable; "
                                     "pass --allow-mixed to mix them anyway");
        }
    }
}

CsvData this_build_rows() {
    CsvData d;
    d.rows.emplace_back();
    for (const auto& [name, value] : provenance_values()) {
        d.header.push_back(name);
        d.rows.back().push_back(value);
    }
    return d;
}

namespace {

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
        std::set<std::string> n;
        for (const ColumnSpec& col : result_column_table())
            if (col.kind == ColumnKind::Number) n.insert(col.name);
        return n;
    }();
    const size_t id = column_index(d, "combo_id", path);
    auto optional_column = [&](const char* name) {
        const auto it = std::find(d.header.begin(), d.header.end(), name);
        return it == d.header.end() ? std::optional<size_t>() : size_t(it - d.header.begin());
    };
    const std::optional<size_t> status = optional_column("status"), params = optional_column("params");
    // Parameter columns (between params and status) hold what the config gave.
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
// combination's repetitions before its row), both under OUT's locks, and the record of
// their inputs; without repetitions (or a known record) an OUT.reps.csv (OUT.inputs.csv)
// left from an earlier file is removed, never left beside the new OUT.
void write_output(const std::string& out, const std::vector<CsvData>& results, const std::vector<CsvData>* reps,
                  const std::optional<RunInputs>& inputs) {
    require_results_name(out);
    const std::string reps_out = repetitions_path(out);
    require_inputs_path_free(out);  // before the locks make OUT
    OutputLock lock({out, reps_out});
    remove_inputs(out);
    if (reps) write_parts(reps_out, *reps);
    else fs::remove(reps_out);
    write_parts(out, results);
    if (inputs) write_inputs(out, *inputs);
}

// Every file a merge reads, under shared locks: a run still writing one holds its lock.
InputLock lock_inputs(const std::vector<std::string>& inputs) {
    std::vector<std::string> files;
    for (const auto& in : inputs) files.insert(files.end(), {in, repetitions_path(in), inputs_path(in)});
    return InputLock(files);
}

// The record of inputs that every file shares. Files measured from other contents (a config
// edited between shards, a mesh file replaced) or without a record to compare are refused
// unless allow_mixed, which gives nullopt: the output's inputs are then unknown.
std::optional<RunInputs> common_inputs(const std::vector<std::string>& files, bool allow_mixed) {
    std::vector<std::optional<RunInputs>> records;
    for (const auto& f : files) records.push_back(read_inputs(f));
    if (files.size() == 1) return records.front();
    for (size_t i = 0; i < files.size(); ++i) {
        std::string why;
        if (!records[i])
            why = files[i] + " has no record of the inputs it was measured from (" + inputs_path(files[i]) +
                "; written by an older build?), so its contents cannot be compared with the others'";
        else if (records[0] && i > 0)
            if (const std::string d = inputs_differences(*records[0], files[0], *records[i], files[i]); !d.empty())
                why = files[0] + " and " + files[i] + " were measured from different inputs (" + d +
                    "): their rows are of different contents under the same names";
        if (why.empty()) continue;
        if (allow_mixed) return std::nullopt;
        throw std::runtime_error(why + "; pass --allow-mixed to merge them anyway");
    }
    return records.front();
}

// Refuses rows of different configs (the `config` column): shards of one run share it.
void check_same_config(const std::vector<CsvData>& data, const std::vector<std::string>& paths) {
    std::map<std::string, std::string> seen;  // config -> the first file with it
    for (size_t f = 0; f < data.size(); ++f) {
        const auto col = std::find(data[f].header.begin(), data[f].header.end(), "config");
        if (col == data[f].header.end()) continue;
        for (const auto& r : data[f].rows) seen.emplace(r[size_t(col - data[f].header.begin())], paths[f]);
    }
    if (seen.size() < 2) return;
    std::string values;
    for (const auto& [config, file] : seen) values += "\n  '" + config + "' (" + file + ")";
    throw std::runtime_error("the inputs hold rows of different configs:" + values +
                             "\nshards of one run share their config; pass --allow-mixed to merge them anyway");
}

}  // namespace

size_t merge_results(const std::string& out, const std::vector<std::string>& inputs, bool allow_mixed) {
    if (inputs.empty()) throw std::runtime_error("nothing to merge");
    for (const auto& in : inputs)
        if (fs::exists(out) && fs::exists(in) && fs::equivalent(out, in))
            throw std::runtime_error("the output '" + out + "' is also an input");
    const InputLock locked = lock_inputs(inputs);
    const std::optional<RunInputs> shared = common_inputs(inputs, allow_mixed);
    std::vector<CsvData> data;
    for (const auto& in : inputs) {
        data.push_back(read_csv(in));
        if (auto m = old_header_message(in, data.back().header); !m.empty()) throw std::runtime_error(m);
        if (data.back().incomplete_tail)
            throw std::runtime_error(in + ": the last line is incomplete (an interrupted run?); resume it first");
        if (auto m = header_mismatch(in, data.back().header, data.front().header); !m.empty())
            throw std::runtime_error(m + " (compared with " + inputs.front() + ")");
        check_result_rows(data.back(), in);
    }
    const CsvData& first = data.front();
    const size_t id = column_index(first, "combo_id", inputs.front());
    if (!allow_mixed) {
        check_same_build(data, inputs);
        check_same_config(data, inputs);
    }
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

    write_output(out, data, all_reps ? &reps : nullptr, shared);
    return owner.size();
}

const std::vector<std::string>& takeable_columns() {
    // Counted in a run of its own (callgrind's instructions): the only column another run of
    // the same config measures better. A status, a time or a count taken alone would leave
    // a row whose columns contradict each other.
    static const std::vector<std::string> columns = {"instructions"};
    return columns;
}

size_t take_column(const std::string& out, const std::string& in, const std::string& from, const std::string& column,
                   bool allow_mixed) {
    const auto& takeable = takeable_columns();
    if (std::find(takeable.begin(), takeable.end(), column) == takeable.end()) {
        std::string names;
        for (const auto& c : takeable) append_item(names, ", ", c);
        throw std::runtime_error("column '" + column + "' cannot be taken from another run (takeable: " + names +
                                 "): the row's other columns would no longer agree with it");
    }
    for (const auto& [source, role] : {std::pair{in, "IN"}, std::pair{from, "FROM"}})
        if (fs::exists(out) && fs::exists(source) && fs::equivalent(out, source))
            throw std::runtime_error("the output '" + out + "' is also the input " + role + " ('" + source +
                                     "'): write to another file");
    const InputLock locked = lock_inputs({in, from});
    const std::optional<RunInputs> shared = common_inputs({in, from}, allow_mixed);
    std::vector<CsvData> data = {read_csv(in), read_csv(from)};
    for (size_t f = 0; f < 2; ++f) {
        const std::string& path = f == 0 ? in : from;
        if (auto m = old_header_message(path, data[f].header); !m.empty()) throw std::runtime_error(m);
        // As merge: a cut last row is the run's to finish, not ours to drop while its
        // repetitions stay in the copy.
        if (data[f].incomplete_tail)
            throw std::runtime_error(path + ": the last line is incomplete (an interrupted run?); resume it first");
    }
    if (auto m = header_mismatch(from, data[1].header, data[0].header); !m.empty())
        throw std::runtime_error(m + " (compared with " + in + ")");
    check_result_rows(data[0], in);
    check_result_rows(data[1], from);  // the taken values among them: numbers or empty
    if (!allow_mixed) {
        check_same_build(data, {in, from});
        check_same_config(data, {in, from});
    }
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
    if (fs::exists(repetitions_path(in))) {
        reps.push_back(read_csv(repetitions_path(in)));
        check_no_orphans(data[0], in, reps.back(), repetitions_path(in));
    }
    write_output(out, {data[0]}, reps.empty() ? nullptr : &reps, shared);
    return taken;
}

size_t convert_results(const std::string& old_csv, const std::string& new_csv) {
    if (fs::exists(new_csv) && fs::equivalent(old_csv, new_csv))
        throw std::runtime_error("the output '" + new_csv + "' is the input: the check needs the old file");
    require_results_name(new_csv);
    // Never over another file: NEW and its companions may be a run's results, repetitions
    // or record of inputs that a conversion would replace (or, for the record, remove).
    for (const std::string& out : {new_csv, repetitions_path(new_csv), inputs_path(new_csv)})
        if (fs::exists(fs::symlink_status(out)))
            throw std::runtime_error("the output '" + out + "' exists: choose another NEW, or remove it");
    const CsvData old = read_csv(old_csv);
    if (old.incomplete_tail)
        throw std::runtime_error(old_csv + ": the last line is incomplete (an interrupted run?); resume it first");
    if (!status_position(old.header)) throw std::runtime_error(old_csv + ": not a results file (no params and status)");
    if (!is_old_results_header(old.header))
        throw std::runtime_error(old_csv + ": already has the current column names; nothing to convert");
    std::vector<std::string> header = old.header;
    std::vector<std::vector<std::string>> rows = old.rows;
    // The label after `accel`, of each row's structure and parameters (the registry's).
    std::optional<size_t> label_at;
    if (lacks_label(header)) {
        const size_t accel = size_t(std::find(header.begin(), header.end(), "accel") - header.begin());
        const auto params = std::find(header.begin(), header.end(), "params");
        const size_t params_at = size_t(params - header.begin());
        label_at = accel + 1;
        for (auto& r : rows) {
            const std::string label =
                accel < r.size() ? registry_label(r[accel], params_at < r.size() ? r[params_at] : "") : "";
            r.insert(r.begin() + long(std::min(*label_at, r.size())), label);
        }
        header.insert(header.begin() + long(*label_at), "label");
    }
    // The added columns after their predecessors, with the value of an older row.
    std::vector<size_t> added_at;
    for (const AddedColumn& c : missing_added_columns(header)) {
        const size_t at = size_t(std::find(header.begin(), header.end(), c.after) - header.begin()) + 1;
        for (size_t& a : added_at)
            if (a >= at) ++a;
        added_at.push_back(at);
        for (auto& r : rows) r.insert(r.begin() + long(std::min(at, r.size())), c.old_value);
        header.insert(header.begin() + long(at), c.name);
    }
    for (size_t i = *status_position(header) + 1; i < header.size(); ++i)
        if (const RenamedColumn* r = renamed_from(header[i])) header[i] = r->new_name;
    for (const RenamedColumn& r : renamed_columns())
        if (std::count(header.begin(), header.end(), r.new_name) > 1)
            throw std::runtime_error(old_csv + ": column " + r.new_name + " would be there twice");

    const std::string old_reps = repetitions_path(old_csv), new_reps = repetitions_path(new_csv);
    const bool reps = fs::exists(old_reps);
    {
        OutputLock lock({new_csv, new_reps});
        if (reps) {
            // Written first, as a run writes a combination's repetitions before its row.
            if (!fs::path(new_reps).parent_path().empty()) fs::create_directories(fs::path(new_reps).parent_path());
            // Over the empty file the lock made (checked absent before), nothing else.
            fs::copy_file(old_reps, new_reps, fs::copy_options::overwrite_existing);
        } else {
            fs::remove(new_reps);  // the empty file the lock made: there are no repetitions
        }
        write_parts(new_csv, {CsvData{header, rows, 0, false}});
        // Without a record beside OLD none is written; nothing beside NEW is removed (none
        // was there: checked above), so no file this command did not write is touched.
        if (const auto inputs = read_inputs(old_csv)) write_inputs(new_csv, *inputs);
    }

    // The check: the file as a reader sees it, against the old one cell by cell.
    const CsvData got = read_csv(new_csv);
    auto fail = [&](const std::string& what) {
        throw std::runtime_error(new_csv + ": the conversion check failed: " + what);
    };
    if (got.incomplete_tail) fail("the last line is incomplete");
    if (got.header != header) fail(header_mismatch(new_csv, got.header, header));
    if (got.rows.size() != old.rows.size())
        fail(std::to_string(got.rows.size()) + " rows, " + old_csv + " has " + std::to_string(old.rows.size()));
    for (size_t i = 0; i < old.rows.size(); ++i) {
        std::vector<std::string> back = got.rows[i];
        std::vector<size_t> inserted = added_at;
        if (label_at) inserted.push_back(*label_at);
        std::sort(inserted.rbegin(), inserted.rend());  // the last first: the others keep their place
        for (size_t at : inserted)
            if (at < back.size()) back.erase(back.begin() + long(at));
        if (back != old.rows[i]) fail("row " + std::to_string(i + 1) + " differs from " + old_csv + "'s");
    }
    if (reps && read_csv(new_reps).rows.size() != read_csv(old_reps).rows.size())
        fail(new_reps + " has another row count than " + old_reps);
    return got.rows.size();
}

}  // namespace accelbench
