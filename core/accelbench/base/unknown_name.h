// The message of every lookup by name that fails — accelerators, procedural scenes,
// robustness cases, config keys: "unknown <what> '<name>'<hint> (known: a, b, c)", so a
// user always sees what would have been accepted.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace accelbench {

inline std::string unknown_name(std::string_view what, std::string_view name, const std::vector<std::string>& known,
                                std::string_view hint = {}) {
    std::string s = "unknown ";
    s.append(what).append(" '").append(name).append("'").append(hint).append(" (known: ");
    for (size_t i = 0; i < known.size(); ++i) s.append(i ? ", " : "").append(known[i]);
    return s.append(")");
}

// The names of a registry's entries, e.g. names_of(accelerator_registry(), &AcceleratorInfo::name).
template <class Entries, class Key>
std::vector<std::string> names_of(const Entries& entries, Key key) {
    std::vector<std::string> names;
    for (const auto& e : entries) names.push_back(std::invoke(key, e));
    return names;
}

}  // namespace accelbench
