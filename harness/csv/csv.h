// CSV as RFC 4180 has it: fields with a comma, a double quote, CR or LF are quoted, quotes
// inside doubled. Lines end with LF.
// Our own: libcsv, the C CSV parser Debian packages, hands rows to callbacks without where
// each ends in the file, which a resumed run needs to cut a torn last line.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace accelbench {

std::string csv_field(const std::string& value);
// The fields joined by commas, with the line's LF.
std::string csv_line(const std::vector<std::string>& fields);

struct CsvData {
    std::vector<std::string> header;
    std::vector<std::vector<std::string>> rows;
    // Bytes up to the end of the last complete line. A process killed while writing can
    // leave a last line without its LF: that line is not in `rows`, and complete_bytes
    // tells a resumed run where to cut the file.
    uint64_t complete_bytes = 0;
    bool incomplete_tail = false;
};

// Reads a whole CSV file. Throws std::runtime_error naming file:line for a row whose
// field count differs from the header's or for a file without a header.
CsvData read_csv(const std::string& path);

}  // namespace accelbench
