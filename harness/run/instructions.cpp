#include "run/instructions.h"

#include <unistd.h>
#include <valgrind/callgrind.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>

namespace fs = std::filesystem;

namespace accelbench {

bool running_on_valgrind() { return RUNNING_ON_VALGRIND != 0; }

CallgrindRegion::CallgrindRegion(std::string out_file, std::string tag)
    // The pid keeps dumps of an earlier run into the same file name from matching.
    : out_file_(std::move(out_file)), description_("accelbench " + tag + " pid " + std::to_string(getpid())) {}

void CallgrindRegion::start() {
    CALLGRIND_ZERO_STATS;
    CALLGRIND_START_INSTRUMENTATION;
}

uint64_t CallgrindRegion::stop() {
    CALLGRIND_STOP_INSTRUMENTATION;
    CALLGRIND_DUMP_STATS_AT(description_.c_str());
    return read_callgrind_dump(out_file_, description_);
}

namespace {

// The first number after `key` ("totals: 123 ..." -> 123, Ir being the first event).
std::optional<uint64_t> first_count(const std::string& line, const std::string& key) {
    if (line.rfind(key, 0) != 0) return std::nullopt;
    const std::string rest = line.substr(key.size());
    const size_t b = rest.find_first_not_of(' ');
    if (b == std::string::npos || !std::isdigit(static_cast<unsigned char>(rest[b]))) return std::nullopt;
    return std::stoull(rest.substr(b));
}

}  // namespace

uint64_t read_callgrind_dump(const std::string& out_file, const std::string& description) {
    // callgrind writes the n-th dump of a run to OUT.n (and the one at exit to OUT).
    const fs::path out(out_file);
    const fs::path dir = out.has_parent_path() ? out.parent_path() : fs::path(".");
    const std::string prefix = out.filename().string() + ".";
    const std::string wanted = "desc: Trigger: Client Request: " + description;
    if (fs::is_directory(dir))
        for (const auto& e : fs::directory_iterator(dir)) {
            const std::string name = e.path().filename().string();
            if (name.rfind(prefix, 0) != 0) continue;
            std::ifstream in(e.path());
            bool ours = false;
            std::optional<uint64_t> totals, summary;
            for (std::string line; std::getline(in, line);) {
                if (line == wanted) ours = true;
                else if (auto v = first_count(line, "totals:")) totals = v;
                else if (auto v = first_count(line, "summary:")) summary = v;
            }
            if (!ours) continue;
            if (totals) return *totals;
            if (summary) return *summary;
            throw std::runtime_error("callgrind dump " + e.path().string() + " has no totals: or summary: line");
        }
    throw std::runtime_error("no callgrind dump '" + description + "' in " + out_file +
                             ".<part>: run under valgrind --tool=callgrind --callgrind-out-file=" + out_file);
}

}  // namespace accelbench
