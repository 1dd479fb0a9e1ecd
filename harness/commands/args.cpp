#include "commands/args.h"
#include "commands/cli.h"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <utility>

#include "accelbench/base/params.h"

namespace accelbench {

Args::Args(std::string command, std::string usage, int argc, char** argv)
    : command_(std::move(command)), usage_(std::move(usage)), argv_(argv, argv + argc) {}

bool Args::flag(std::string_view name) {
    if (current() != name) return false;
    ++at_;
    return true;
}

bool Args::value(std::string_view name, std::string& out) {
    const std::string& a = current();
    std::string given;
    if (a.size() > name.size() && a.compare(0, name.size(), name) == 0 && a[name.size()] == '=') {
        given = a.substr(name.size() + 1);
        ++at_;
    } else if (a == name) {
        if (at_ + 1 >= argv_.size()) throw ArgError(a + " needs a value");
        given = argv_[at_ + 1];
        at_ += 2;
    } else {
        return false;
    }
    // An empty value (`--out=` or --benchmark_out="$UNSET") would read as the option not
    // given: the results would go to the default file, the JSON nowhere, silently.
    if (given.empty()) throw ArgError(std::string(name) + " needs a value, got an empty one");
    out = std::move(given);
    return true;
}

bool Args::value(std::string_view name, int& out, int lo, int hi) {
    std::string text;
    if (!value(name, text)) return false;
    // The one rule for how a number is written (configs and k=v parameters alike): 010 is
    // refused naming the form, not read as 10.
    if (const std::string why = number_form_problem(text); !why.empty()) throw ArgError(std::string(name) + ": " + why);
    int v = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size() || v < lo || v > hi)
        throw ArgError(std::string(name) + " expects an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                       "], got '" + text + "'");
    out = v;
    return true;
}

bool Args::positional(std::vector<std::string>& out) {
    if (current().empty() || current()[0] == '-') return false;
    out.push_back(current());
    ++at_;
    return true;
}

std::string Args::take() { return argv_[at_++]; }

bool Args::unknown() const {
    const std::string& a = current();
    throw ArgError(!a.empty() && a[0] == '-' ? "unknown option '" + a + "'" : "unexpected argument '" + a + "'");
}

int usage_error(std::string_view command, std::string_view usage, std::string_view message) {
    std::fprintf(stderr, "accelbench %.*s: %.*s\n%.*s", int(command.size()), command.data(), int(message.size()),
                 message.data(), int(usage.size()), usage.data());
    return 2;
}

int Args::error(const std::string& message) const { return usage_error(command_, usage_, message); }

void Args::print_usage() const { std::printf("%s", usage_.c_str()); }

int with_output_checked(const char* command, int status) {
    std::cout.flush();
    const bool failed = !std::cout.good() || std::fflush(stdout) != 0 || std::ferror(stdout);
    if (!failed) return status;
    const int err = errno;
    std::fprintf(stderr, "accelbench %s: writing to standard output failed%s%s\n", command, err ? ": " : "",
                 err ? std::strerror(err) : "");
    return status == 0 ? 1 : status;
}

}  // namespace accelbench
