#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>

#include "accelbench/accel/registry.h"
#include "accelbench/base/unknown_name.h"
#include "config/config_sections.h"

namespace accelbench {

namespace {

// parse_param's messages start with "accelerator 'x', parameter 'y': "; the key path
// already says that.
std::string strip_param_prefix(const std::string& msg) {
    const std::string marker = "', parameter '";
    size_t at = msg.find(marker);
    if (at == std::string::npos) return msg;
    size_t end = msg.find("': ", at + marker.size());
    return end == std::string::npos ? msg : msg.substr(end + 3);
}

// "an int value", "a float value", ...
std::string a_value_of(ParamType t) {
    const std::string type = to_string(t);
    return (type.front() == 'i' || type.front() == 'e' ? "an " : "a ") + type + " value";
}

}  // namespace

std::optional<std::string> read_param_value(Checker& c, const YAML::Node& n, const std::string& path,
                                            const std::string& owner, const ParamSpec& spec) {
    if (!n.IsScalar()) {
        c.error(n, path, "expected " + a_value_of(spec.type) + ", got " + kind_of(n));
        return std::nullopt;
    }
    if (quoted(n) && spec.type != ParamType::Enum) {
        c.error(n, path, "expected " + a_value_of(spec.type) + ", got the quoted string '" + n.Scalar() + "'");
        return std::nullopt;
    }
    // A default that depends on the scene (the kd-tree's max_depth "auto") can be named, so
    // a zipped group can pair it with other values; it means "not given".
    if (spec.scene_dependent_default && n.Scalar() == spec.default_value) return spec.default_value;
    try {
        return format_param(parse_param(owner, spec, n.Scalar()));
    } catch (const ParamError& e) {
        c.error(n, path, strip_param_prefix(e.what()));
        return std::nullopt;
    }
}

const ParamSpec* find_spec(const std::vector<ParamSpec>& specs, const std::string& name) {
    for (const auto& s : specs)
        if (s.name == name) return &s;
    return nullptr;
}

std::vector<std::string> spec_names(const std::vector<ParamSpec>& specs) {
    std::vector<std::string> names;
    for (const auto& s : specs) names.push_back(s.name);
    return names;
}

std::string format_float(double v) { return format_param(ParamValue(v)); }

namespace {

std::vector<std::string> split_group(const std::string& key) {
    std::vector<std::string> names;
    std::string inner = key.substr(1, key.size() - 2);
    size_t start = 0;
    for (;;) {
        size_t comma = inner.find(',', start);
        std::string part = inner.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        size_t b = part.find_first_not_of(" \t"), e = part.find_last_not_of(" \t");
        names.push_back(b == std::string::npos ? "" : part.substr(b, e - b + 1));
        if (comma == std::string::npos) return names;
        start = comma + 1;
    }
}

// A range (for grid searches; analysis/README.md "Grid search"; the analysis reads the
// values from `accelbench run --dry-run=json`, never expands a range itself): {from: a, to: b, step: s} is a, a+s, ... while <= b (with a
// 1e-9 x s slack); {from: a, to: b, scale: log2|log10} is a, 2a, 4a, ... (10a, ...)
// while <= b. Integer from, to (and step) give integers, other values are rounded to 12
// significant digits (0.1 steps read 0.3, not 0.30000000000000004).
bool read_range(Checker& c, const YAML::Node& n, const std::string& path, const std::string& accel,
                const ParamSpec& spec, ParamAxis& axis) {
    constexpr size_t kMaxValues = 10000;  // a typo like step: 0.0001 must not hang the expansion
    Fields f(c, n, path, {"from", "to", "step", "scale"});
    const auto* from = f.require("from");
    const auto* to = f.require("to");
    if (!from || !to) return false;
    auto lo = read_number(c, from->value, f.child("from"), -1e300, 1e300, false);
    auto hi = read_number(c, to->value, f.child("to"), -1e300, 1e300, false);
    if (!lo || !hi) return false;
    auto integral = [](const YAML::Node& v) {
        int64_t x;
        const std::string& t = v.Scalar();
        auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), x);
        return ec == std::errc() && p == t.data() + t.size();
    };
    if (*lo > *hi) {
        c.error(n, path, "`from` (" + from->value.Scalar() + ") is above `to` (" + to->value.Scalar() + ")");
        return false;
    }
    const auto* step = f.find("step");
    const auto* scale = f.find("scale");
    if (bool(step) == bool(scale)) {
        c.error(n, path, "a range gives exactly one of `step` or `scale` (log2, log10)");
        return false;
    }
    std::vector<double> values;
    bool integers = integral(from->value) && integral(to->value);
    if (step) {
        auto s = read_number(c, step->value, f.child("step"), 0, 1e300, true);
        if (!s) return false;
        integers &= integral(step->value);
        const double count = std::floor((*hi - *lo) / *s + 1e-9) + 1;
        for (double i = 0; i < count && values.size() <= kMaxValues; ++i) values.push_back(*lo + i * *s);
    } else {
        auto name = read_string(c, scale->value, f.child("scale"));
        if (!name) return false;
        if (*name != "log2" && *name != "log10") {
            c.error(scale->value, f.child("scale"), "scale is log2 or log10, got '" + *name + "'");
            return false;
        }
        if (*lo <= 0) {
            c.error(from->value, f.child("from"), "a " + *name + " range starts above 0");
            return false;
        }
        const double base = *name == "log2" ? 2.0 : 10.0;
        integers = integral(from->value);
        const double count = std::floor(std::log(*hi / *lo) / std::log(base) + 1e-9) + 1;
        for (double i = 0; i < count && values.size() <= kMaxValues; ++i) values.push_back(*lo * std::pow(base, i));
    }
    if (values.size() > kMaxValues) {
        c.error(n, path, "the range has more than " + std::to_string(kMaxValues) + " values");
        return false;
    }
    bool ok = true;
    for (double v : values) {
        char text[40];
        if (integers) std::snprintf(text, sizeof text, "%.0f", v);
        else std::snprintf(text, sizeof text, "%.12g", v);
        try {
            const std::string canonical = format_param(parse_param(accel, spec, text));
            if (std::find(axis.values.begin(), axis.values.end(), std::vector<std::string>{canonical}) ==
                axis.values.end())
                axis.values.push_back({canonical});
        } catch (const ParamError& e) {
            c.error(n, path, "the range's value " + std::string(text) + ": " + strip_param_prefix(e.what()));
            ok = false;
        }
    }
    return ok;
}

// A parameter's values: a scalar (one value) or a list of scalars.
bool read_values(Checker& c, const YAML::Node& n, const std::string& path, const std::string& accel,
                 const ParamSpec& spec, ParamAxis& axis) {
    if (n.IsScalar()) {
        auto v = read_param_value(c, n, path, accel, spec);
        if (v) axis.values.push_back({*v});
        return bool(v);
    }
    if (n.IsMap()) return read_range(c, n, path, accel, spec, axis);
    if (!n.IsSequence() || n.size() == 0) {
        c.error(n, path,
                std::string("expected a value, a non-empty list of values or a range, got ") +
                    (n.IsSequence() ? "an empty list" : kind_of(n)));
        return false;
    }
    bool ok = true;
    for (size_t j = 0; j < n.size(); ++j) {
        const std::string p = path + "[" + std::to_string(j) + "]";
        auto v = read_param_value(c, n[j], p, accel, spec);
        if (!v) {
            ok = false;
            continue;
        }
        if (std::find(axis.values.begin(), axis.values.end(), std::vector<std::string>{*v}) != axis.values.end()) {
            c.error(n[j], p, "value " + *v + " is listed twice");
            ok = false;
            continue;
        }
        axis.values.push_back({*v});
    }
    return ok;
}

// A zipped group's values: a list of tuples, one value per named parameter.
bool read_group_values(Checker& c, const YAML::Node& n, const std::string& base, const std::string& key,
                       const std::string& accel, const std::vector<const ParamSpec*>& specs, ParamAxis& axis) {
    const std::string path = base + "." + key;
    if (!n.IsSequence() || n.size() == 0) {
        c.error(n, path,
                "expected a non-empty list of tuples, e.g. [[1, 28], [10, 20]], got " +
                    std::string(n.IsSequence() ? "an empty list" : kind_of(n)));
        return false;
    }
    bool ok = true;
    for (size_t j = 0; j < n.size(); ++j) {
        const YAML::Node& t = n[j];
        const std::string tp = path + "[" + std::to_string(j) + "]";
        if (!t.IsSequence() || t.size() != specs.size()) {
            c.error(t, tp,
                    "expected a tuple of " + std::to_string(specs.size()) + " values (" + key + "), got " +
                        (t.IsSequence() ? "a list of " + std::to_string(t.size()) : std::string(kind_of(t))));
            ok = false;
            continue;
        }
        std::vector<std::string> tuple;
        for (size_t k = 0; k < specs.size(); ++k) {
            auto v = read_param_value(c, t[k], base + "." + specs[k]->name + "[" + std::to_string(j) + "]", accel,
                                      *specs[k]);
            if (v) tuple.push_back(*v);
        }
        if (tuple.size() != specs.size()) {
            ok = false;
            continue;
        }
        if (std::find(axis.values.begin(), axis.values.end(), tuple) != axis.values.end()) {
            c.error(t, tp, "this tuple is listed twice");
            ok = false;
            continue;
        }
        axis.values.push_back(std::move(tuple));
    }
    return ok;
}

}  // namespace

bool read_param_axes(Checker& c, const YAML::Node& node, const std::string& base, const AcceleratorInfo& info,
                     std::vector<ParamAxis>& axes) {
    Fields pf(c, node, base, {});
    bool ok = pf.ok();
    std::map<std::string, std::string> used;  // parameter -> the key that gave it
    for (const auto& e : pf.entries()) {
        const bool group = e.key.size() >= 2 && e.key.front() == '[' && e.key.back() == ']';
        const std::vector<std::string> names = group ? split_group(e.key) : std::vector<std::string>{e.key};
        if (group && names.size() < 2) {
            c.error(e.key_node, pf.child(e.key),
                    "a zipped group names two or more parameters, e.g. \"[max_prims, max_depth]\"");
            ok = false;
            continue;
        }
        bool names_ok = true;
        std::vector<const ParamSpec*> specs;
        for (const auto& pn : names) {
            const ParamSpec* spec = find_spec(info.params, pn);
            if (!spec) {
                const auto known = spec_names(info.params);
                c.error(e.key_node, base + "." + pn,
                        "accelerator '" + info.name + "' has no parameter '" + pn + "'" + did_you_mean(pn, known) +
                            (known.empty() ? " (it takes none)" : " (it has: " + join_names(known) + ")"));
                names_ok = false;
            } else if (auto u = used.find(pn); u != used.end()) {
                c.error(e.key_node, base + "." + pn,
                        "parameter '" + pn + "' is given twice (also in '" + u->second + "')");
                names_ok = false;
            } else {
                used.emplace(pn, e.key);
                specs.push_back(spec);
            }
        }
        if (!names_ok) {
            ok = false;
            continue;
        }
        ParamAxis axis;
        axis.names = names;
        if (group) ok &= read_group_values(c, e.value, base, e.key, info.name, specs, axis);
        else ok &= read_values(c, e.value, base + "." + names[0], info.name, *specs[0], axis);
        axes.push_back(std::move(axis));
    }
    return ok;
}

}  // namespace accelbench
