#include "util/checked_yaml.h"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "accelbench/base/params.h"
#include "accelbench/base/unknown_name.h"
#include "util/text.h"

namespace accelbench {

std::string format_issue(const ConfigIssue& issue) {
    std::string s = issue.mark.file;
    for (int n : {issue.mark.line, issue.mark.column})
        if (n > 0) {
            s += ':';
            s += std::to_string(n);
        }
    s += ": ";
    if (!issue.key_path.empty()) {
        s += issue.key_path;
        s += ": ";
    }
    s += issue.message;
    return s;
}

namespace {

std::string join_issues(const std::vector<ConfigIssue>& issues) {
    std::string s;
    for (const auto& i : issues) {
        if (!s.empty()) s += '\n';
        s += format_issue(i);
    }
    return s;
}

}  // namespace

ConfigError::ConfigError(std::vector<ConfigIssue> issues)
    : std::runtime_error(join_issues(issues)), issues_(std::move(issues)) {}

ConfigError single_issue(const std::string& file, int line, int column, const std::string& message) {
    std::vector<ConfigIssue> issues(1);
    issues[0].mark.file = file;
    issues[0].mark.line = line;
    issues[0].mark.column = column;
    issues[0].message = message;
    return ConfigError(std::move(issues));
}

namespace {

// Where each document of a YAML stream starts, from the parser's events (nothing is built).
class DocumentStarts final : public YAML::EventHandler {
public:
    std::vector<YAML::Mark> marks;
    void OnDocumentStart(const YAML::Mark& mark) override { marks.push_back(mark); }
    void OnDocumentEnd() override {}
    void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
    void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
    void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
    void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
    void OnSequenceEnd() override {}
    void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
    void OnMapEnd() override {}
};

}  // namespace

// Not YAML::LoadAllFromFile: yaml-cpp 0.7.0's LoadAll never returns on some malformed
// streams — a lone ',' is one (jbeder/yaml-cpp issue 1040, fixed upstream by pull request
// 1319, after Debian 12's 0.7.0): its parser reports an empty document at the same place
// again and again, and LoadAll keeps every one. The config fuzz test's process grew to
// 24 GB before the kernel's OOM killer stopped it (a mutation of configs/scaling-quick.yaml).
// So the documents are counted from the parser's events, two at most, a second one that
// starts where the first did is that stuck parser (a syntax error at that place), and only
// the first document is built (YAML::Load).
YAML::Node load_yaml_document(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw single_issue(path, 0, 0, "cannot open the config file");
    std::ostringstream bytes;
    bytes << in.rdbuf();
    const std::string text = bytes.str();
    YAML::Node document;
    try {
        std::istringstream stream(text);
        YAML::Parser parser(stream);
        DocumentStarts starts;
        while (starts.marks.size() < 2 && parser.HandleNextDocument(starts)) {}
        if (starts.marks.size() == 2) {
            const YAML::Mark& m = starts.marks[1];
            const int line = m.line >= 0 ? m.line + 1 : 0, column = m.column >= 0 ? m.column + 1 : 0;
            if (m.pos == starts.marks[0].pos)
                throw single_issue(path, line, column, "YAML syntax error: the parser cannot read past this point");
            // A second document (after `---`) would be ignored by a reader of the first:
            // refused, so that nothing the user wrote is silently dropped.
            throw single_issue(
                path, line, column,
                "a second YAML document (after '---'): a config is one document; join them or use two files");
        }
        if (!starts.marks.empty()) document = YAML::Load(text);
    } catch (const YAML::Exception& e) {
        throw single_issue(path, e.mark.line + 1, e.mark.column + 1, "YAML syntax error: " + e.msg);
    }
    if (!document || document.IsNull()) throw single_issue(path, 1, 1, "the config is empty");
    return document;
}

const char* kind_of(const YAML::Node& n) {
    switch (n.Type()) {
        case YAML::NodeType::Map: return "a mapping";
        case YAML::NodeType::Sequence: return "a list";
        case YAML::NodeType::Scalar: return "a scalar";
        case YAML::NodeType::Null: return "nothing (null)";
        default: return "an undefined value";
    }
}

// A string by its form: quoted ("4", '4', tag "!") or tagged `!!str 4`.
bool quoted(const YAML::Node& n) { return n.Tag() == "!" || n.Tag() == "tag:yaml.org,2002:str"; }

Fields::Fields(Checker& c, const YAML::Node& map, std::string path, const std::vector<std::string>& allowed)
    : c_(c), map_(map), path_(std::move(path)) {
    if (!map.IsMap()) {
        c.error(map, path_, std::string("expected a mapping, got ") + kind_of(map));
        return;
    }
    ok_ = true;
    std::map<std::string, YAML::Mark> seen;
    std::vector<YAML::Node> merges;
    // Range-for, not `it->first`: yaml-cpp's iterator::operator-> returns a proxy that
    // holds the key/value pair by value, so a reference to `it->first` dangles as soon
    // as the statement ends (ASan: stack-use-after-scope). `*it` yields the pair by
    // value and the range-for keeps it alive for the whole body.
    for (const auto& entry : map) {
        const YAML::Node& k = entry.first;
        std::string key;
        if (k.IsScalar()) key = k.Scalar();
        else if (k.IsSequence()) key = flow_key(k);  // [max_prims, max_depth]: ...
        else {
            c.error(k, path_, std::string("a key must be a name, got ") + kind_of(k));
            continue;
        }
        if (key == "<<" && k.IsScalar() && !quoted(k)) {  // a merge key: read after the mapping's own keys
            merges.push_back(entry.second);
            continue;
        }
        if (auto s = seen.find(key); s != seen.end()) {
            c.error(k, child(key),
                    "duplicate key '" + key + "' (first given at line " + std::to_string(s->second.line + 1) +
                        ", column " + std::to_string(s->second.column + 1) + ")");
            continue;
        }
        seen.emplace(key, k.Mark());
        if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
            c.error(
                k, child(key),
                "unknown key '" + key + "'" + did_you_mean(key, allowed) + "; allowed here: " + join_names(allowed));
            continue;
        }
        entries_.push_back({key, k, entry.second});
    }
    // YAML merge keys (`<<: *defaults`, or a list of aliases): the merged mapping's keys
    // that this mapping does not give itself, the first of a list winning (the YAML 1.1
    // merge key type, which yaml-cpp leaves to its user).
    for (const YAML::Node& merged : merges) {
        std::vector<YAML::Node> sources;
        if (merged.IsMap()) sources.push_back(merged);
        else if (merged.IsSequence())
            for (const auto& item : merged) sources.push_back(item);
        for (const YAML::Node& source : sources) {
            if (!source.IsMap()) {
                ok_ = false;  // its keys are unknown: "missing key" would name the wrong cause
                c.error(source, child("<<"),
                        std::string("a merge key ('<<') takes a mapping (an alias such as *defaults) or a list of "
                                    "them, got ") +
                            kind_of(source));
                continue;
            }
            for (const auto& entry : source) {
                const YAML::Node& k = entry.first;
                if (!k.IsScalar() || seen.count(k.Scalar())) continue;
                const std::string& key = k.Scalar();
                seen.emplace(key, k.Mark());
                if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
                    c.error(k, child(key),
                            "unknown key '" + key + "' (merged with '<<')" + did_you_mean(key, allowed) +
                                "; allowed here: " + join_names(allowed));
                    continue;
                }
                entries_.push_back({key, k, entry.second});
            }
        }
        if (sources.empty()) {
            ok_ = false;
            c.error(merged, child("<<"),
                    std::string("a merge key ('<<') takes a mapping (an alias such as *defaults) or a list of them, "
                                "got ") +
                        kind_of(merged));
        }
    }
}

const Fields::Entry* Fields::find(const std::string& key) const {
    for (const auto& e : entries_)
        if (e.key == key) return &e;
    return nullptr;
}

const Fields::Entry* Fields::require(const std::string& key) const {
    const Entry* e = find(key);
    if (!e && ok_) c_.error(map_, child(key), "missing key '" + key + "'");
    return e;
}

std::string Fields::flow_key(const YAML::Node& k) {
    std::string s = "[";
    for (size_t i = 0; i < k.size(); ++i) {
        if (i) s += ", ";
        s += k[i].IsScalar() ? k[i].Scalar() : std::string("?");
    }
    return s + "]";
}

std::optional<std::string> read_string(Checker& c, const YAML::Node& n, const std::string& path) {
    if (!n.IsScalar()) {
        c.error(n, path, std::string("expected a string, got ") + kind_of(n));
        return std::nullopt;
    }
    if (n.Scalar().empty()) {
        c.error(n, path, "expected a non-empty string");
        return std::nullopt;
    }
    return n.Scalar();
}

namespace {

// The text of a plain scalar written as a number, or nullptr after saying why it is none
// (a quoted scalar is a string; `expected` is what the key takes, e.g. "an integer in [0, 8]").
const std::string* number_text(Checker& c, const YAML::Node& n, const std::string& path, const std::string& expected) {
    if (!n.IsScalar() || quoted(n)) {
        c.error(n, path,
                "expected " + expected + ", got " +
                    (n.IsScalar() ? "the string '" + n.Scalar() + "'" : std::string(kind_of(n))));
        return nullptr;
    }
    if (const std::string why = number_form_problem(n.Scalar()); !why.empty()) {
        c.error(n, path, why);
        return nullptr;
    }
    return &n.Scalar();
}

}  // namespace

std::optional<int64_t> read_int(Checker& c, const YAML::Node& n, const std::string& path, int64_t lo, int64_t hi) {
    const std::string range = concat("[", std::to_string(lo), ", ", std::to_string(hi), "]");
    const std::string* text = number_text(c, n, path, "an integer in " + range);
    if (!text) return std::nullopt;
    const std::string& t = *text;
    int64_t v = 0;
    auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || p != t.data() + t.size()) {
        c.error(n, path, "expected an integer in " + range + ", got '" + t + "'");
        return std::nullopt;
    }
    if (v < lo || v > hi) {
        c.error(n, path, "value " + t + " is out of range " + range);
        return std::nullopt;
    }
    return v;
}

// A number in (lo, hi] when lo_open, else [lo, hi].
std::optional<double> read_number(Checker& c, const YAML::Node& n, const std::string& path, double lo, double hi,
                                  bool lo_open) {
    char range[96];
    std::snprintf(range, sizeof range, "%s%g, %g]", lo_open ? "(" : "[", lo, hi);
    const std::string* text = number_text(c, n, path, std::string("a number in ") + range);
    if (!text) return std::nullopt;
    const std::string& t = *text;
    char* end = nullptr;
    double v = std::strtod(t.c_str(), &end);
    if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(v)) {
        c.error(n, path, std::string("expected a number in ") + range + ", got '" + t + "'");
        return std::nullopt;
    }
    if (v > hi || v < lo || (lo_open && v == lo)) {
        c.error(n, path, "value " + t + " is out of range " + range);
        return std::nullopt;
    }
    return v;
}

std::optional<bool> read_bool(Checker& c, const YAML::Node& n, const std::string& path) {
    if (bool v = false; n.IsScalar() && !quoted(n) && parse_bool_text(n.Scalar(), v)) return v;
    // A quoted "true" is a string: said so, or the message would refuse what it reads as a bool.
    c.error(n, path,
            std::string("expected true or false, got ") +
                (!n.IsScalar() ? std::string(kind_of(n)) : (quoted(n) ? "the string '" : "'") + n.Scalar() + "'"));
    return std::nullopt;
}

std::optional<float> read_float(Checker& c, const YAML::Node& n, const std::string& path, double lo, double hi,
                                bool lo_open) {
    const auto v = read_number(c, n, path, lo, hi, lo_open);
    if (!v) return std::nullopt;
    if (const std::string why = float_conversion_problem(*v, n.Scalar()); !why.empty()) {
        c.error(n, path, why);
        return std::nullopt;
    }
    return float(*v);
}

std::optional<Vec3> read_vec3(Checker& c, const YAML::Node& n, const std::string& path) {
    if (!n.IsSequence() || n.size() != 3) {
        c.error(n, path,
                std::string("expected a list of three numbers [x, y, z], got ") +
                    (n.IsSequence() ? "a list of " + std::to_string(n.size()) : std::string(kind_of(n))));
        return std::nullopt;
    }
    Vec3 v;
    for (int i = 0; i < 3; ++i) {
        auto x = read_float(c, n[i], path + "[" + std::to_string(i) + "]", -1e30, 1e30, false);
        if (!x) return std::nullopt;
        v[i] = float(*x);
    }
    return v;
}

// parse_param's messages start with "accelerator 'x', parameter 'y': "; the key path

}  // namespace accelbench
