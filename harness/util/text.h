// Building messages from pieces. concat() appends left to right into one string; it
// exists because GCC 12 at -O3 reports a false -Wrestrict on `"literal" + std::string&&`
// (GCC bug 105329), which -Werror turns into a build failure.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace accelbench {

template <class... Parts>
std::string concat(const Parts&... parts) {
    std::string s;
    (s.append(std::string_view(parts)), ...);
    return s;
}

}  // namespace accelbench

namespace accelbench {

// Appends an item to a separated list: the separator first unless the list is empty.
template <class... Parts>
void append_item(std::string& list, std::string_view separator, const Parts&... parts) {
    if (!list.empty()) list.append(separator);
    (list.append(std::string_view(parts)), ...);
}

}  // namespace accelbench

namespace accelbench {

// A number in printf's %.<digits>g: the CSV's measured values (9 digits, enough for a
// float's round trip), rates and ratios (6), a value as a user wrote it (6, "0.1").
inline std::string number_text(double v, int digits = 9) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

}  // namespace accelbench

namespace accelbench {

// A JSON string literal of `text` (RFC 8259: quotes, backslashes and control characters
// escaped; other bytes as they are, so UTF-8 stays UTF-8).
inline std::string json_quoted(std::string_view text) {
    std::string s = "\"";
    for (unsigned char ch : text) {
        if (ch == '"' || ch == '\\') s.append(1, '\\').append(1, char(ch));
        else if (ch == '\n') s += "\\n";
        else if (ch == '\t') s += "\\t";
        else if (ch < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", ch);
            s += buf;
        } else s += char(ch);
    }
    return s + "\"";
}

}  // namespace accelbench

namespace accelbench {

// Why `text` cannot be a label (a model's label, a config's name or description), or "":
// a control character (U+0000-U+001F, U+007F), which would break the one-line forms a label
// takes (a CSV cell, the wire between processes, a terminal line, a page's text).
inline std::string control_character_problem(std::string_view text) {
    for (size_t i = 0; i < text.size(); ++i)
        if (const auto ch = static_cast<unsigned char>(text[i]); ch < 0x20 || ch == 0x7f) {
            char buf[96];
            std::snprintf(buf, sizeof buf,
                          "holds the control character U+%04X at byte %zu: labels are one line of text", unsigned(ch),
                          i + 1);
            return buf;
        }
    return "";
}

}  // namespace accelbench
