#include "accelbench/base/params.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace accelbench {

const char* to_string(ParamType t) {
    switch (t) {
        case ParamType::Int: return "int";
        case ParamType::Float: return "float";
        case ParamType::Enum: return "enum";
        case ParamType::Bool: return "bool";
    }
    return "?";
}

namespace {

std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
    return s;
}

std::string range_text(const ParamSpec& s) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "[%g, %g]", s.min, s.max);
    return buf;
}

}  // namespace

std::string format_param(const ParamValue& v) {
    if (auto* i = std::get_if<int64_t>(&v)) return std::to_string(*i);
    if (auto* d = std::get_if<double>(&v)) {
        // The shortest text that reads back to the same double, without an exponent
        // where plain notation is as short ("80", "0.5", "1e-05" stays as is).
        char buf[64];
        auto [end, ec] = std::to_chars(buf, buf + sizeof buf, *d);
        return ec == std::errc() ? std::string(buf, end) : std::to_string(*d);
    }
    if (auto* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
    return std::get<std::string>(v);
}

std::string number_form_problem(const std::string& text) {
    size_t i = text.size() > 0 && (text[0] == '-' || text[0] == '+') ? 1 : 0;
    if (text.size() >= i + 2 && text[i] == '0') {
        const char c = char(text[i + 1] | 0x20);
        if (c == 'x' || c == 'o' || c == 'b')
            return "'" + text + "' is " +
                (c == 'x'       ? "hexadecimal"
                     : c == 'o' ? "octal"
                                : "binary") +
                ", which configs and parameters do not take (YAML readers disagree on it): write it in decimal";
        if (text[i + 1] >= '0' && text[i + 1] <= '9')
            return "'" + text + "' has a leading zero, which YAML readers read differently (010 is 8 in PyYAML, " +
                "10 in yaml-cpp): write it without the leading zero";
    }
    return "";
}

bool rounds_to_finite_float(double value) {
    // FLT_MAX plus half its spacing (2^104 at the top): round-to-nearest takes a value below
    // it to FLT_MAX, one at or above it to infinity (FLT_MAX's odd mantissa loses the tie).
    constexpr double kOverflow = double(std::numeric_limits<float>::max()) + 0x1p103;
    return std::fabs(value) < kOverflow;
}

float round_to_float(double value) {
    const double top = double(std::numeric_limits<float>::max());
    return float(std::clamp(value, -top, top));  // what nearest rounding gives for |value| in (FLT_MAX, kOverflow)
}

std::string float_conversion_problem(double value, const std::string& text) {
    // Judged on the float the value rounds to, not on the double: programs print FLT_MAX
    // as 3.4028235e38 and FLT_MIN as 1.1754944e-38, both just past the limits as doubles.
    if (!rounds_to_finite_float(value))
        return "value " + text + " is beyond the float range (at most 3.4028235e38, FLT_MAX)";
    if (const float f = round_to_float(value); value != 0 && !std::isnormal(f))
        return "value " + text + " does not survive conversion to float (it becomes " +
            (f == 0.0f ? std::string("0") : std::string("a subnormal")) +
            "; the smallest normal float is 1.1754944e-38)";
    return "";
}

bool parse_bool_text(const std::string& text, bool& value) {
    for (const char* t : {"true", "True", "TRUE", "yes", "Yes", "YES", "on", "On", "ON"})
        if (text == t) return value = true, true;
    for (const char* f : {"false", "False", "FALSE", "no", "No", "NO", "off", "Off", "OFF"})
        if (text == f) return value = false, true;
    return false;
}

ParamValue parse_param(const std::string& owner, const ParamSpec& spec, const std::string& text,
                       const char* owner_kind) {
    const std::string where = std::string(owner_kind) + " '" + owner + "', parameter '" + spec.name + "': ";
    switch (spec.type) {
        case ParamType::Int: {
            if (const std::string why = number_form_problem(text); !why.empty()) throw ParamError(where + why);
            int64_t v = 0;
            auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
            if (ec != std::errc() || p != text.data() + text.size())
                throw ParamError(where + "expected an integer, got '" + text + "'");
            if (double(v) < spec.min || double(v) > spec.max)
                throw ParamError(where + "value " + text + " is out of range " + range_text(spec));
            return v;
        }
        case ParamType::Float: {
            if (const std::string why = number_form_problem(text); !why.empty()) throw ParamError(where + why);
            char* end = nullptr;
            double v = std::strtod(text.c_str(), &end);
            if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v))
                throw ParamError(where + "expected a finite number, got '" + text + "'");
            if (const std::string why = float_conversion_problem(v, text); !why.empty()) throw ParamError(where + why);
            if (v < spec.min || v > spec.max)
                throw ParamError(where + "value " + text + " is out of range " + range_text(spec));
            return v;
        }
        case ParamType::Enum:
            for (const auto& c : spec.choices)
                if (c == text) return text;
            throw ParamError(where + "'" + text + "' is not one of {" + join(spec.choices) + "}");
        case ParamType::Bool:
            if (bool b = false; parse_bool_text(text, b)) return b;
            if (text == "1" || text == "0") return text == "1";
            throw ParamError(where + "expected true or false, got '" + text + "'");
    }
    throw ParamError(where + "unknown type");
}

ParamSet resolve_params(const std::string& owner, const std::vector<ParamSpec>& specs,
                        const std::map<std::string, std::string>& given, const char* owner_kind) {
    for (const auto& [name, value] : given) {
        bool known = false;
        for (const auto& s : specs) known |= s.name == name;
        if (!known) {
            std::vector<std::string> names;
            for (const auto& s : specs) names.push_back(s.name);
            throw ParamError(std::string(owner_kind) + " '" + owner + "' has no parameter '" + name + "'" +
                             (names.empty() ? std::string(" (it takes none)") : " (it has: " + join(names) + ")"));
        }
    }
    ParamSet set;
    for (const auto& s : specs) {
        auto it = given.find(s.name);
        const bool user = it != given.end();
        set.given_[s.name] = user;
        if (!user && s.scene_dependent_default) {
            set.text_.emplace_back(s.name, s.default_value);
            continue;
        }
        ParamValue v = parse_param(owner, s, user ? it->second : s.default_value, owner_kind);
        set.text_.emplace_back(s.name, format_param(v));
        set.values_.emplace(s.name, std::move(v));
    }
    return set;
}

const ParamValue& ParamSet::at(const std::string& name) const {
    auto it = values_.find(name);
    if (it == values_.end())
        throw ParamError("parameter '" + name + "' has no value (not declared, or its default depends on the scene)");
    return it->second;
}
int64_t ParamSet::get_int(const std::string& name) const { return std::get<int64_t>(at(name)); }
double ParamSet::get_float(const std::string& name) const { return std::get<double>(at(name)); }
const std::string& ParamSet::get_enum(const std::string& name) const { return std::get<std::string>(at(name)); }
bool ParamSet::get_bool(const std::string& name) const { return std::get<bool>(at(name)); }
bool ParamSet::given(const std::string& name) const {
    auto it = given_.find(name);
    return it != given_.end() && it->second;
}

std::string ParamSet::canonical() const {
    std::string s;
    for (const auto& [k, v] : text_) s += (s.empty() ? "" : ";") + k + "=" + v;
    return s;
}

}  // namespace accelbench
