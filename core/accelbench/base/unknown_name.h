// The message of every lookup by name that fails — accelerators, procedural scenes,
// robustness cases, config keys: "unknown <what> '<name>'<hint> (known: a, b, c)", so a
// user always sees what would have been accepted; did_you_mean() is the hint for a close
// misspelling, one rule for every such message (the config reader's keys included).
#pragma once

#include <algorithm>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace accelbench {

// The names joined by `separator`: the "(known: ...)" and "allowed here: ..." lists.
inline std::string join_names(const std::vector<std::string>& names, std::string_view separator = ", ") {
    std::string s;
    for (size_t i = 0; i < names.size(); ++i) s.append(i ? separator : "").append(names[i]);
    return s;
}

inline std::string unknown_name(std::string_view what, std::string_view name, const std::vector<std::string>& known,
                                std::string_view hint = {}) {
    std::string s = "unknown ";
    s.append(what).append(" '").append(name).append("'").append(hint).append(" (known: ");
    return s.append(join_names(known)).append(")");
}

// Levenshtein distance (insertions, deletions, substitutions of one character).
inline size_t edit_distance(std::string_view a, std::string_view b) {
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j)
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

// " (did you mean 'x'?)" for the first known name within two edits of `name` (only close
// misspellings: a name far from every known one gets no hint), else "".
inline std::string did_you_mean(std::string_view name, const std::vector<std::string>& known) {
    const std::string* best = nullptr;
    size_t best_d = 3;
    for (const auto& k : known)
        if (size_t d = edit_distance(name, k); d < best_d) best_d = d, best = &k;
    return best ? " (did you mean '" + *best + "'?)" : "";
}

// The names of a registry's entries, e.g. names_of(accelerator_registry(), &AcceleratorInfo::name).
template <class Entries, class Key>
std::vector<std::string> names_of(const Entries& entries, Key key) {
    std::vector<std::string> names;
    for (const auto& e : entries) names.push_back(std::invoke(key, e));
    return names;
}

}  // namespace accelbench
