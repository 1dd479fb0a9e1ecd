// The one argument parser of every command (the shape of pbrt-v4's util/args.h): a command
// walks its arguments with an Args and asks, at each, whether it is one of its options;
// `-h`/`--help` prints the command's usage, and a usage error reads the same in every
// command ("accelbench CMD: what is wrong", then the usage on stderr, exit 2).
//
//     Args args("models", kUsage, argc, argv);
//     bool fetch = false;
//     if (auto code = args.walk([&] { fetch = args.flag("--fetch") || args.unknown(); })) return *code;
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace accelbench {

// A command line that cannot be followed (thrown by Args' readers and caught by walk()).
struct ArgError : std::invalid_argument {
    using std::invalid_argument::invalid_argument;
};

// "accelbench COMMAND: message", then the usage, on stderr; returns 2, the exit code of a
// command line that cannot be followed.
int usage_error(std::string_view command, std::string_view usage, std::string_view message);

class Args {
public:
    Args(std::string command, std::string usage, int argc, char** argv);

    // Calls `each` at every argument; `each` takes it with one of the readers below or calls
    // unknown(). Returns the exit code when the command should end now: 0 after -h/--help
    // (the usage on stdout), 2 after a usage error (reported); nullopt when every argument
    // was taken.
    template <class F>
    std::optional<int> walk(F&& each) {
        try {
            while (at_ < argv_.size()) {
                if (current() == "-h" || current() == "--help") {
                    print_usage();
                    return 0;
                }
                const size_t before = at_;
                each();
                if (at_ == before) unknown();
            }
        } catch (const ArgError& e) {
            return error(e.what());
        }
        return std::nullopt;
    }

    // The argument being looked at.
    const std::string& current() const { return argv_[at_]; }

    // `--name`: true, and the argument is taken.
    bool flag(std::string_view name);
    // `--name VALUE` or `--name=VALUE`: true with the value in `out`; a missing value is an
    // ArgError.
    bool value(std::string_view name, std::string& out);
    // The same for an integer in [lo, hi]; anything else is an ArgError.
    bool value(std::string_view name, int& out, int lo, int hi);
    // An argument that is not an option (does not start with '-'): appended to `out`.
    bool positional(std::vector<std::string>& out);
    // Takes the current argument as it is (a command's own forms, such as run's
    // --benchmark_* flags).
    std::string take();
    // The current argument is none of the command's: an ArgError, "unknown option '--x'"
    // or "unexpected argument 'x'". Declared bool so it ends an || chain.
    [[noreturn]] bool unknown() const;

    // A usage error found after the walk (a missing argument): reported; returns 2.
    int error(const std::string& message) const;

private:
    void print_usage() const;

    std::string command_, usage_;
    std::vector<std::string> argv_;
    size_t at_ = 0;
};

}  // namespace accelbench
