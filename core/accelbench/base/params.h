// Accelerator parameters: each structure declares its parameters (name, type, default,
// range or choices); user input (CLI "k=v", YAML values) is validated against that list
// before anything is built. A parameter a structure does not have is an error, never
// silently ignored.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace accelbench {

enum class ParamType { Int, Float, Enum, Bool };

const char* to_string(ParamType t);

struct ParamSpec {
    std::string name;
    ParamType type = ParamType::Int;
    std::string default_value;         // as text, parsed like user input
    std::vector<std::string> choices;  // Enum only
    double min = -1e300, max = 1e300;  // Int/Float only, inclusive
    std::string help;
    // A default that depends on the scene (e.g. the kd-tree's 8 + 1.3 log2 N): then
    // default_value is shown as text (e.g. "auto") and the structure computes it.
    bool scene_dependent_default = false;
};

// An Enum parameter's names, listed once in an array in the enum's order: that array
// gives both the declared choices and the parser's enum value.
template <size_t N>
std::vector<std::string> enum_choices(const std::array<std::string_view, N>& names) {
    return {names.begin(), names.end()};
}

// The index of `name` in `names` (the ParamSet has checked that it is one of them).
template <size_t N>
size_t enum_index(const std::array<std::string_view, N>& names, const std::string& name) {
    return size_t(std::find(names.begin(), names.end(), name) - names.begin()) % N;
}

using ParamValue = std::variant<int64_t, double, std::string, bool>;

struct ParamError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// A validated set of values: every declared parameter has a value (the given one or the
// default); nothing else is present.
class ParamSet {
public:
    int64_t get_int(const std::string& name) const;
    double get_float(const std::string& name) const;
    const std::string& get_enum(const std::string& name) const;
    bool get_bool(const std::string& name) const;
    // True when the user gave the value (false: the default applies).
    bool given(const std::string& name) const;
    // Canonical text "k=v;k=v" in declaration order, as the CSV's `params` column.
    std::string canonical() const;
    const std::vector<std::pair<std::string, std::string>>& items() const { return text_; }

private:
    friend ParamSet resolve_params(const std::string&, const std::vector<ParamSpec>&,
                                   const std::map<std::string, std::string>&, const char*);
    const ParamValue& at(const std::string& name) const;
    std::map<std::string, ParamValue> values_;
    std::map<std::string, bool> given_;
    std::vector<std::pair<std::string, std::string>> text_;
};

// Parses one value as the spec's type; throws ParamError with a message that names the
// owner ("accelerator 'bvh'", "procedural scene 'forest'"), the parameter and what was
// expected.
ParamValue parse_param(const std::string& owner, const ParamSpec& spec, const std::string& text,
                       const char* owner_kind = "accelerator");

// Validates user values against the specs and fills in defaults.
ParamSet resolve_params(const std::string& owner, const std::vector<ParamSpec>& specs,
                        const std::map<std::string, std::string>& given, const char* owner_kind = "accelerator");

// The one rule for how a number is written, in configs, CLI "k=v" and parameters alike:
// why `text` is refused before it is read as a number, or "" when it is not. Refused:
// hexadecimal, octal and binary prefixes (0x10 is 16 in YAML 1.2, a string in YAML 1.1
// readers, and was taken by some keys and not others), and an integer part with a leading
// zero (010 is 8 in PyYAML and 10 in yaml-cpp).
std::string number_form_problem(const std::string& text);

// Why `value`, written as `text`, cannot be used as a float, or "": a non-zero value that
// rounds to zero or to a subnormal float (1e-50 becomes 0), or one beyond the float range.
std::string float_conversion_problem(double value, const std::string& text);
// Whether `value` rounds to a finite float (nearest rounding: up to FLT_MAX plus half an
// ulp, so the printed 3.4028235e38 does), and the float it rounds to.
bool rounds_to_finite_float(double value);
float round_to_float(double value);

// True for the YAML 1.2 core schema's booleans (true True TRUE), and the YAML 1.1 forms
// configs already use (yes on, in the same three cases); `value` receives it.
bool parse_bool_text(const std::string& text, bool& value);

// Canonical text of a value (integers without decimals, floats round-trippable).
std::string format_param(const ParamValue& v);

}  // namespace accelbench
