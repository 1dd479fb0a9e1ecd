// The quoted includes of a source file with their line numbers, for the layering tests of
// the core (layering_test) and the harness (harness_layering_test).
#pragma once

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

namespace accelbench::testing {

struct QuotedInclude {
    int line;          // 1-based
    std::string path;  // as written between the quotes
};

inline std::vector<QuotedInclude> quoted_includes(const std::filesystem::path& file) {
    static const std::regex include_re(R"(^\s*#\s*include\s+"([^"]+)\")");
    std::vector<QuotedInclude> out;
    std::ifstream in(file);
    std::string text;
    int n = 0;
    while (std::getline(in, text)) {
        ++n;
        std::smatch m;
        if (std::regex_search(text, m, include_re)) out.push_back({n, m[1].str()});
    }
    return out;
}

}  // namespace accelbench::testing
