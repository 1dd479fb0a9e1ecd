#include "config/ray_file.h"

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "accelbench/base/params.h"

namespace accelbench {

namespace {

constexpr size_t kMaxIssues = 20;

std::string trim(const std::string& s) {
    size_t b = s.find_first_not_of(" \t\r");
    if (b == std::string::npos) return "";
    size_t e = s.find_last_not_of(" \t\r");
    return s.substr(b, e - b + 1);
}

// Splits at commas, remembering the 1-based column where each field starts (not csv.h's
// reader: a ray file holds only numbers, and its errors name the column of the field).
std::vector<std::pair<std::string, int>> split_fields(const std::string& line) {
    std::vector<std::pair<std::string, int>> out;
    size_t start = 0;
    for (;;) {
        size_t comma = line.find(',', start);
        out.emplace_back(trim(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)),
                         int(start) + 1);
        if (comma == std::string::npos) return out;
        start = comma + 1;
    }
}

// Text as a message shows it: bytes that are not printable ASCII as \xNN, so that an
// invisible character in a header is seen.
std::string visible(const std::string& s) {
    std::string out;
    for (unsigned char c : s) {
        if (c >= 0x20 && c < 0x7f) {
            out += char(c);
        } else {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02X", unsigned(c));
            out += hex;
        }
    }
    return out;
}

}  // namespace

RayFileContents read_ray_file(const std::string& path, const std::string& display) {
    RayFileContents result;
    auto issue = [&](int line, int column, const std::string& msg) {
        if (result.issues.size() < kMaxIssues) result.issues.push_back({{display, line, column}, "", msg});
    };
    std::ifstream in(path);
    if (!in) {
        issue(0, 0, "cannot open ray file '" + path + "'");
        return result;
    }
    std::string line;
    int line_no = 0;
    size_t fields = 0;  // 6 or 7 once the header is read
    while (std::getline(in, line)) {
        ++line_no;
        // A UTF-8 byte-order mark, as spreadsheet programs write it, is not part of the
        // header; UTF-16 (whose mark starts FF FE or FE FF) is another encoding, named.
        if (line_no == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
        if (line_no == 1 && (line.rfind("\xFF\xFE", 0) == 0 || line.rfind("\xFE\xFF", 0) == 0)) {
            issue(1, 1, "the ray file is UTF-16 (it starts with a UTF-16 byte-order mark): save it as UTF-8 or ASCII");
            return result;
        }
        const std::string text = trim(line);
        if (text.empty()) continue;
        if (fields == 0) {
            if (text == "ox,oy,oz,dx,dy,dz") fields = 6;
            else if (text == "ox,oy,oz,dx,dy,dz,tmax") fields = 7;
            else {
                issue(
                    line_no, 1,
                    "expected the header 'ox,oy,oz,dx,dy,dz' or 'ox,oy,oz,dx,dy,dz,tmax', got '" + visible(text) + "'");
                return result;
            }
            continue;
        }
        auto parts = split_fields(line);
        if (parts.size() != fields) {
            issue(
                line_no, 1,
                "expected " + std::to_string(fields) + " comma-separated numbers, got " + std::to_string(parts.size()));
            continue;
        }
        float v[7] = {0, 0, 0, 0, 0, 0, kInfinity};
        bool ok = true;
        for (size_t i = 0; i < fields; ++i) {
            const std::string& f = parts[i].first;
            char* end = nullptr;
            const double d = std::strtod(f.c_str(), &end);
            if (f.empty() || end != f.c_str() + f.size()) {
                issue(line_no, parts[i].second, "field " + std::to_string(i + 1) + " is not a number: '" + f + "'");
                ok = false;
                break;
            }
            // inf and nan are taken as written; a number that is none as a float (1e-50 read
            // as 0, 1e999 as inf) or a hexadecimal float (the number rule of configs) is not.
            const size_t sign = f[0] == '-' || f[0] == '+' ? 1 : 0;
            const bool literal = f.size() > sign && std::isalpha(static_cast<unsigned char>(f[sign]));
            std::string why = !literal && f.find_first_of("xX") != std::string::npos ? number_form_problem(f) : "";
            if (why.empty() && !literal) why = float_conversion_problem(d, f);
            if (!why.empty()) {
                issue(line_no, parts[i].second, "field " + std::to_string(i + 1) + ": " + why);
                ok = false;
                break;
            }
            v[i] = literal ? float(d) : round_to_float(d);
        }
        if (!ok) continue;
        Ray r;
        r.org = {v[0], v[1], v[2]};
        r.dir = {v[3], v[4], v[5]};
        r.tmin = 0.0f;
        r.tmax = v[6];
        result.rays.push_back(r);
    }
    if (fields == 0) issue(line_no, 0, "empty ray file: expected a header line and at least one ray");
    else if (result.rays.empty() && result.issues.empty()) issue(line_no, 0, "the ray file has a header but no rays");
    return result;
}

}  // namespace accelbench
