// The classes and functions of a C++ source file with the lines they span, found by
// matching braces, for the size test (code_shape_test). Not a parser: comments, string
// and character literals and preprocessor lines are blanked first; then each `{` met at
// file, namespace or class scope is classified by the text before it (its head) as a
// class, a function, or anything else (enum, initializer, extern block). What is inside a
// function — lambdas, local classes — counts as the function's own lines.
#pragma once

#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace accelbench::testing {

struct CodeBlock {
    enum Kind { Class, Function } kind;
    std::string name;  // the class's name, or the function's name (a macro's with its arguments)
    int first_line;    // of the opening brace, 1-based
    int last_line;     // of the closing brace
    int lines() const { return last_line - first_line + 1; }
};

namespace code_shape_detail {

// Comments, literals and preprocessor lines become spaces; newlines stay, so line numbers do.
inline std::string blank_non_code(const std::string& src) {
    std::string out = src;
    size_t i = 0;
    const size_t n = src.size();
    bool line_start = true;
    auto blank = [&](size_t from, size_t to) {
        for (size_t k = from; k < to && k < n; ++k)
            if (out[k] != '\n') out[k] = ' ';
    };
    while (i < n) {
        const char c = src[i];
        if (c == '\n') {
            line_start = true;
            ++i;
            continue;
        }
        if (line_start && (c == ' ' || c == '\t')) {
            ++i;
            continue;
        }
        if (line_start && c == '#') {  // a directive, with its continuation lines
            size_t e = i;
            while (e < n && !(src[e] == '\n' && src[e - 1] != '\\')) ++e;
            blank(i, e);
            i = e;
            continue;
        }
        line_start = false;
        if (c == '/' && i + 1 < n && src[i + 1] == '/') {
            size_t e = src.find('\n', i);
            if (e == std::string::npos) e = n;
            blank(i, e);
            i = e;
        } else if (c == '/' && i + 1 < n && src[i + 1] == '*') {
            size_t e = src.find("*/", i + 2);
            e = e == std::string::npos ? n : e + 2;
            blank(i, e);
            i = e;
        } else if (c == 'R' && i + 1 < n && src[i + 1] == '"' && (i == 0 || !std::isalnum((unsigned char)src[i - 1]))) {
            const size_t open = src.find('(', i + 2);
            std::string close(1, ')');
            close.append(src, i + 2, open - (i + 2));
            close.push_back('"');
            size_t e = src.find(close, open);
            e = e == std::string::npos ? n : e + close.size();
            blank(i, e);
            i = e;
        } else if (c == '"' || (c == '\'' && !(i > 0 && std::isxdigit((unsigned char)src[i - 1])))) {
            // (a quote after a hex digit is a digit separator: 1'000)
            size_t e = i + 1;
            while (e < n && src[e] != c) e += src[e] == '\\' ? 2 : 1;
            blank(i, e + 1);
            i = e + 1;
        } else {
            ++i;
        }
    }
    return out;
}

inline bool is_word(const std::string& s, size_t at, const std::string& w) {
    if (s.compare(at, w.size(), w) != 0) return false;
    const auto ident = [](char ch) { return std::isalnum((unsigned char)ch) || ch == '_'; };
    return (at == 0 || !ident(s[at - 1])) && (at + w.size() >= s.size() || !ident(s[at + w.size()]));
}

// The head with a leading `template <...>` removed and whitespace squeezed.
inline std::string squeeze(const std::string& head) {
    std::string s;
    for (char ch : head) {
        if (std::isspace((unsigned char)ch)) {
            if (!s.empty() && s.back() != ' ') s += ' ';
        } else {
            s += ch;
        }
    }
    while (!s.empty() && s.back() == ' ') s.pop_back();
    while (!s.empty() && s.front() == ' ') s.erase(0, 1);
    while (is_word(s, 0, "template")) {
        size_t k = s.find('<');
        int depth = 0;
        for (; k < s.size(); ++k) {
            depth += s[k] == '<' ? 1 : s[k] == '>' ? -1 : 0;
            if (depth == 0) break;
        }
        s = k < s.size() ? s.substr(k + 1) : "";
        while (!s.empty() && s.front() == ' ') s.erase(0, 1);
    }
    return s;
}

enum class HeadKind { Namespace, Class, Function, MemberInit, Other };

struct Head {
    HeadKind kind;
    std::string name;
};

inline std::string identifier_before(const std::string& s, size_t end) {
    size_t b = end;
    while (b > 0 && s[b - 1] == ' ') --b;
    size_t a = b;
    while (a > 0 && (std::isalnum((unsigned char)s[a - 1]) || s[a - 1] == '_' || s[a - 1] == ':' || s[a - 1] == '~'))
        --a;
    return s.substr(a, b - a);
}

inline Head classify(const std::string& raw) {
    const std::string s = squeeze(raw);
    if (is_word(s, 0, "namespace") || is_word(s, 0, "extern")) return {HeadKind::Namespace, ""};
    // Scan at bracket depth 0 for '(', a lone '=' and the class keywords.
    int depth = 0;
    size_t first_paren = std::string::npos, last_close = std::string::npos, class_kw = std::string::npos;
    bool assignment = false, is_enum = false;
    for (size_t k = 0; k < s.size(); ++k) {
        const char ch = s[k];
        if (ch == '(' || ch == '[') {
            if (depth == 0 && ch == '(' && first_paren == std::string::npos) first_paren = k;
            ++depth;
        } else if (ch == ')' || ch == ']') {
            --depth;
            if (depth == 0 && ch == ')') last_close = k;
        } else if (depth == 0 && ch == '=' && first_paren == std::string::npos) {
            const char prev = k ? s[k - 1] : ' ', next = k + 1 < s.size() ? s[k + 1] : ' ';
            const bool operator_name = s.rfind("operator", k) != std::string::npos && k >= 8 &&
                s.find_first_not_of(" =!<>+-*/%&|^", s.rfind("operator", k) + 8) >= k;
            if (!operator_name && next != '=' && prev != '=' && prev != '!' && prev != '<' && prev != '>')
                assignment = true;
        } else if (depth == 0 && class_kw == std::string::npos) {
            if (is_word(s, k, "enum")) is_enum = true;
            for (const char* kw : {"class", "struct", "union"})
                if (is_word(s, k, kw)) class_kw = k;
        }
    }
    if (assignment || is_enum) return {HeadKind::Other, ""};
    if (class_kw != std::string::npos && first_paren == std::string::npos) {
        std::istringstream words(s.substr(class_kw));
        std::string kw, name;
        words >> kw >> name;
        while (name == "final" || name.rfind("alignas", 0) == 0 || name.rfind("[[", 0) == 0) words >> name;
        return {HeadKind::Class, name.substr(0, name.find_first_of(":<{"))};
    }
    if (first_paren == std::string::npos || last_close == std::string::npos) return {HeadKind::Other, ""};
    // After the parameter list, a member-initializer list `: a_(x), b_` that ends in a name
    // means this brace initializes a member; the body's brace comes later.
    const std::string tail = s.substr(last_close + 1);
    size_t colon = std::string::npos;
    for (size_t k = 0; k < tail.size(); ++k)
        if (tail[k] == ':' && (k + 1 >= tail.size() || tail[k + 1] != ':') && (k == 0 || tail[k - 1] != ':')) {
            colon = k;
            break;
        }
    const char last = s.back();
    if (colon != std::string::npos && (std::isalnum((unsigned char)last) || last == '_' || last == '>'))
        return {HeadKind::MemberInit, ""};
    // In `Foo::Foo(int a) : a_{a}, b_(2) {` the first '(' is the parameter list's.
    std::string name = identifier_before(s, first_paren);
    const size_t op = s.rfind("operator", first_paren);
    if (name.empty() && op != std::string::npos) {
        // operator==, operator(): the name runs to the parameter list.
        const size_t params = s.compare(op + 8, 2, "()") == 0 ? op + 10 : first_paren;
        name = s.substr(op, params - op);
    }
    bool macro = !name.empty();
    for (char ch : name) macro &= std::isupper((unsigned char)ch) || ch == '_' || std::isdigit((unsigned char)ch);
    if (macro) {
        int d = 0;
        size_t k = first_paren;
        for (; k < s.size(); ++k) {
            d += s[k] == '(' ? 1 : s[k] == ')' ? -1 : 0;
            if (d == 0) break;
        }
        name = s.substr(first_paren - name.size(), k + 1 - (first_paren - name.size()));
    }
    return {HeadKind::Function, name};
}

}  // namespace code_shape_detail

inline std::vector<CodeBlock> code_blocks(const std::string& source) {
    using namespace code_shape_detail;
    const std::string s = blank_non_code(source);
    struct Frame {
        HeadKind kind;
        std::string name;
        int line;
        size_t head_start;  // for MemberInit: where the enclosing head began
    };
    std::vector<Frame> stack;
    std::vector<CodeBlock> out;
    int line = 1;
    size_t head_start = 0;  // start of the text since the last ; { } at a scope that holds heads
    auto opaque = [&] {
        return !stack.empty() && stack.back().kind != HeadKind::Namespace && stack.back().kind != HeadKind::Class;
    };
    for (size_t i = 0; i < s.size(); ++i) {
        const char c = s[i];
        if (c == '\n') {
            ++line;
            continue;
        }
        if (c == '{') {
            if (opaque()) {
                stack.push_back({HeadKind::Other, "", line, 0});
                continue;
            }
            const Head h = classify(s.substr(head_start, i - head_start));
            stack.push_back({h.kind, h.name, line, head_start});
            head_start = i + 1;
        } else if (c == '}') {
            if (stack.empty()) continue;
            const Frame f = stack.back();
            stack.pop_back();
            if (f.kind == HeadKind::Class) out.push_back({CodeBlock::Class, f.name, f.line, line});
            if (f.kind == HeadKind::Function) out.push_back({CodeBlock::Function, f.name, f.line, line});
            if (opaque()) continue;
            // A member's brace initializer continues its constructor's head.
            head_start = f.kind == HeadKind::MemberInit ? f.head_start : i + 1;
        } else if (c == ';' && !opaque()) {
            head_start = i + 1;
        } else if (c == ':' && !opaque() && (i + 1 >= s.size() || s[i + 1] != ':') && (i == 0 || s[i - 1] != ':')) {
            // `public:` and the like end a head too.
            const std::string before = squeeze(s.substr(head_start, i - head_start));
            if (before == "public" || before == "private" || before == "protected") head_start = i + 1;
        }
    }
    return out;
}

inline std::vector<CodeBlock> code_blocks(const std::filesystem::path& file) {
    std::ifstream in(file);
    std::stringstream buffer;
    buffer << in.rdbuf();
    return code_blocks(buffer.str());
}

}  // namespace accelbench::testing
