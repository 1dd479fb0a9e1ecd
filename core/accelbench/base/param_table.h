// A structure's parameters, each declared once: one row per parameter with its name, its
// range or choices, its text and the Config member it sets. The member's initializer in
// Config is the default. Both the declared ParamSpecs (what `accelbench list`, the YAML
// reader and the CLI check values against) and Config::from(ParamSet) are loops over the
// rows, so a parameter cannot be declared with one default and read with another.
//
//   const ParamTable<Config>& table() {
//       static const ParamTable<Config> rows = {
//           int_param("max_depth", &Config::max_depth, 0, 1000, "nodes at this depth become leaves"),
//           enum_param("split", &Config::split, kSplitNames, "where a node splits"),
//       };
//       return rows;
//   }
#pragma once

#include <algorithm>
#include <array>
#include <concepts>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "accelbench/base/parallel.h"
#include "accelbench/base/params.h"

namespace accelbench {

// One parameter: its declaration (the default already read from a default Config) and how
// its resolved value is stored into a Config.
template <class Config>
struct ParamRow {
    ParamSpec spec;
    std::function<void(Config&, const ParamSet&)> store;
};

template <class Config>
class ParamTable {
public:
    ParamTable(std::initializer_list<ParamRow<Config>> rows) : rows_(rows) {}

    // The declarations in row order (the order of the CSV's `params` text).
    std::vector<ParamSpec> specs() const {
        std::vector<ParamSpec> out;
        for (const ParamRow<Config>& row : rows_) out.push_back(row.spec);
        return out;
    }

    // A Config with every row's value stored; members without a row keep their initializer.
    Config from(const ParamSet& params) const {
        Config c;
        for (const ParamRow<Config>& row : rows_) row.store(c, params);
        return c;
    }

private:
    std::vector<ParamRow<Config>> rows_;
};

// An integer member, in [min, max].
template <class Config, std::integral T>
requires(!std::same_as<T, bool>) ParamRow<Config> int_param(std::string name, T Config::*member, double min, double max,
                                                            std::string help) {
    return {{name, ParamType::Int, format_param(int64_t(Config{}.*member)), {}, min, max, std::move(help)},
            [name, member](Config& c, const ParamSet& p) { c.*member = T(p.get_int(name)); }};
}

// An integer member whose default depends on the scene or on other parameters: declared as
// "auto" (described in `help`); the member stays empty unless the user gives a value.
template <class Config, std::integral T>
ParamRow<Config> auto_int_param(std::string name, std::optional<T> Config::*member, double min, double max,
                                std::string help) {
    return {{name, ParamType::Int, "auto", {}, min, max, std::move(help), true},
            [name, member](Config& c, const ParamSet& p) {
                if (p.given(name)) c.*member = T(p.get_int(name));
            }};
}

// A thread count: 0 stands for every core of the machine, stored as that number
// (build_thread_count, base/parallel.h).
template <class Config>
ParamRow<Config> threads_param(std::string name, int Config::*member, double max, std::string help) {
    return {{name, ParamType::Int, format_param(int64_t(Config{}.*member)), {}, 0, max, std::move(help)},
            [name, member](Config& c, const ParamSet& p) { c.*member = build_thread_count(p.get_int(name)); }};
}

// A float or double member, in [min, max].
template <class Config, std::floating_point T>
ParamRow<Config> float_param(std::string name, T Config::*member, double min, double max, std::string help) {
    return {{name, ParamType::Float, format_param(double(Config{}.*member)), {}, min, max, std::move(help)},
            [name, member](Config& c, const ParamSet& p) { c.*member = T(p.get_float(name)); }};
}

template <class Config>
ParamRow<Config> bool_param(std::string name, bool Config::*member, std::string help) {
    return {{name, ParamType::Bool, format_param(Config{}.*member), {}, 0, 1, std::move(help)},
            [name, member](Config& c, const ParamSet& p) { c.*member = p.get_bool(name); }};
}

// A member that takes one of N values, each named: names[i] stands for values[i].
template <class Config, class T, size_t N>
ParamRow<Config> choice_param(std::string name, T Config::*member, const std::array<std::string_view, N>& names,
                              const std::array<T, N>& values, std::string help) {
    const size_t d = size_t(std::find(values.begin(), values.end(), Config{}.*member) - values.begin());
    if (d == N) throw std::logic_error("parameter '" + name + "': the Config default is none of its choices");
    return {{name, ParamType::Enum, std::string(names[d]), enum_choices(names), 0, 0, std::move(help)},
            [name, member, names, values](Config& c, const ParamSet& p) {
                c.*member = values[enum_index(names, p.get_enum(name))];
            }};
}

// An enum member whose enumerators are 0 .. N-1 in the order of `names`.
template <class Config, class E, size_t N>
requires std::is_enum_v<E> ParamRow<Config> enum_param(std::string name, E Config::*member,
                                                       const std::array<std::string_view, N>& names, std::string help) {
    std::array<E, N> values{};
    for (size_t i = 0; i < N; ++i) values[i] = E(i);
    return choice_param(std::move(name), member, names, values, std::move(help));
}

}  // namespace accelbench
