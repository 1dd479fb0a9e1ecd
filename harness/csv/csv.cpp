#include "csv/csv.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace accelbench {

std::string csv_field(const std::string& v) {
    if (v.find_first_of(",\"\r\n") == std::string::npos) return v;
    std::string out = "\"";
    for (char ch : v) {
        if (ch == '"') out += '"';
        out += ch;
    }
    out += '"';
    return out;
}

std::string csv_line(const std::vector<std::string>& fields) {
    std::string line;
    for (size_t i = 0; i < fields.size(); ++i) {
        if (i) line += ',';
        line += csv_field(fields[i]);
    }
    line += '\n';
    return line;
}

CsvData read_csv(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot open '" + path + "'");
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();

    CsvData data;
    std::vector<std::string> record;
    std::string field;
    bool in_quotes = false, field_started = false;
    size_t line = 1, record_line = 1;
    auto end_record = [&](size_t end_offset) {
        record.push_back(field);
        field.clear();
        field_started = false;
        if (data.header.empty()) {
            data.header = record;
        } else if (!(record.size() == 1 && record[0].empty())) {  // blank lines are not rows
            if (record.size() != data.header.size())
                throw std::runtime_error(path + ":" + std::to_string(record_line) + ": " +
                                         std::to_string(record.size()) + " fields, the header has " +
                                         std::to_string(data.header.size()));
            data.rows.push_back(record);
        }
        record.clear();
        data.complete_bytes = end_offset;
        record_line = line;
    };
    for (size_t i = 0; i < text.size(); ++i) {
        const char ch = text[i];
        if (in_quotes) {
            if (ch == '"') {
                if (i + 1 < text.size() && text[i + 1] == '"') {
                    field += '"';
                    ++i;
                } else {
                    in_quotes = false;
                }
            } else {
                if (ch == '\n') ++line;
                field += ch;
            }
            continue;
        }
        if (ch == '"' && !field_started) {
            in_quotes = field_started = true;
        } else if (ch == ',') {
            record.push_back(field);
            field.clear();
            field_started = false;
        } else if (ch == '\n') {
            if (!field.empty() && field.back() == '\r') field.pop_back();
            ++line;
            end_record(i + 1);
        } else {
            field += ch;
            field_started = true;
        }
    }
    data.incomplete_tail = !record.empty() || field_started || in_quotes;
    if (data.header.empty()) throw std::runtime_error(path + ": no header line");
    return data;
}

}  // namespace accelbench
