// A checked reader of YAML documents, independent of what the document means: every
// problem becomes one ConfigIssue with the file, line, column and key path
// (`accelerators[2].kdtree.max_depth`), a value of the wrong type says what it got, an
// unknown key gets a did-you-mean hint (unknown_name.h), and the caller collects every
// issue of a document before it refuses it. The benchmark configs (config/) and the model
// registry, configs/models.yaml (models/), are read with these.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "accelbench/base/geometry.h"

namespace accelbench {

// Where in a file something is; line and column are 1-based, 0 when unknown.
struct SourceMark {
    std::string file;
    int line = 0;
    int column = 0;
};

struct ConfigIssue {
    SourceMark mark;
    std::string key_path;  // e.g. "accelerators[2].kdtree.max_depth"; empty for the whole file
    std::string message;
};

// "file:line:column: key.path: message"
std::string format_issue(const ConfigIssue& issue);

// Thrown by load_config (and expansion) with every issue found; what() lists them all,
// one per line.
class ConfigError : public std::runtime_error {
public:
    explicit ConfigError(std::vector<ConfigIssue> issues);
    const std::vector<ConfigIssue>& issues() const { return issues_; }

private:
    std::vector<ConfigIssue> issues_;
};

// A ConfigError of one issue at file:line:column (0: unknown).
ConfigError single_issue(const std::string& file, int line, int column, const std::string& message);

// The document of a YAML file. Throws ConfigError: the file cannot be opened, a syntax
// error (at its line and column), an empty document, a second document.
YAML::Node load_yaml_document(const std::string& path);

// "a mapping", "a list", "a scalar", ...: what a value is, for "expected X, got Y".
const char* kind_of(const YAML::Node& n);

// A quoted scalar ("1", 'x') is a string in YAML: it is never read as a number or bool.
bool quoted(const YAML::Node& n);

// Collects issues while a loader walks the document.
struct Checker {
    std::string file;
    std::vector<ConfigIssue> issues;

    void error(const YAML::Mark& m, const std::string& path, const std::string& msg) {
        issues.push_back({{file, m.line + 1, m.column + 1}, path, msg});
    }
    void error(const YAML::Node& n, const std::string& path, const std::string& msg) { error(n.Mark(), path, msg); }
};

// The entries of one mapping, checked for duplicate and unknown keys. yaml-cpp 0.7 keeps
// both entries of a duplicated key (lookups see the first), so the walk over the entries
// is what finds them. A missing key has no mark of its own: it is reported at the
// mapping's mark.
class Fields {
public:
    struct Entry {
        std::string key;
        YAML::Node key_node;
        YAML::Node value;
    };

    // `allowed` empty: any key (the caller checks them).
    Fields(Checker& c, const YAML::Node& map, std::string path, const std::vector<std::string>& allowed);

    // A mapping whose keys are all known: false when it is no mapping, or a merge key in it
    // merged no mapping (callers then add no "missing key" of their own).
    bool ok() const { return ok_; }
    const std::vector<Entry>& entries() const { return entries_; }
    const Entry* find(const std::string& key) const;
    bool has(const std::string& key) const { return find(key) != nullptr; }
    // The entry, or an issue "missing key" at the mapping.
    const Entry* require(const std::string& key) const;
    std::string child(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
    const std::string& path() const { return path_; }
    const YAML::Node& node() const { return map_; }

    // A flow-sequence key, e.g. `[max_prims, max_depth]`, in the canonical spelling a
    // quoted key uses.
    static std::string flow_key(const YAML::Node& k);

private:
    Checker& c_;
    YAML::Node map_;
    std::string path_;
    bool ok_ = false;
    std::vector<Entry> entries_;
};

// ---- scalar readers: each reports its own issue and returns nullopt -------------------

std::optional<std::string> read_string(Checker& c, const YAML::Node& n, const std::string& path);  // non-empty
std::optional<int64_t> read_int(Checker& c, const YAML::Node& n, const std::string& path, int64_t lo, int64_t hi);
// A finite number in (lo, hi] when lo_open, else [lo, hi].
std::optional<double> read_number(Checker& c, const YAML::Node& n, const std::string& path, double lo, double hi,
                                  bool lo_open);
// A number as read_number, that is also a float: refused when it does not survive the
// conversion (float_conversion_problem: 1e-50 would become 0).
std::optional<float> read_float(Checker& c, const YAML::Node& n, const std::string& path, double lo, double hi,
                                bool lo_open);
// true/yes/on, false/no/off, each also Capitalised and in CAPITALS (YAML 1.2 core: True, TRUE).
std::optional<bool> read_bool(Checker& c, const YAML::Node& n, const std::string& path);
std::optional<Vec3> read_vec3(Checker& c, const YAML::Node& n, const std::string& path);  // [x, y, z]

// A list: `each(item, "path[i]")` for every item; an issue when `n` is not a list or is
// empty (unless may_be_empty).
template <class F>
void read_list(Checker& c, const YAML::Node& n, const std::string& path, F&& each, bool may_be_empty = false) {
    if (!n.IsSequence()) {
        c.error(n, path, std::string("expected a list, got ") + kind_of(n));
        return;
    }
    if (n.size() == 0 && !may_be_empty) c.error(n, path, "the list is empty");
    for (size_t i = 0; i < n.size(); ++i) each(n[i], path + "[" + std::to_string(i) + "]");
}

}  // namespace accelbench
