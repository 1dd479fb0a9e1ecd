// The floating-point mode rays are traced in, a render setting that applies to every
// structure alike (Embree included): IEEE 754 with gradual underflow, or the SSE control
// register's flush-to-zero (FTZ: a denormal result becomes zero) and denormals-are-zero
// (DAZ: a denormal operand reads as zero) bits set, as Embree's documentation asks of every
// thread that calls it (Embree 3 manual, "Performance Recommendations"). The mode is set
// per thread; builds run in the caller's mode, so a tree does not depend on it.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace accelbench {

// The modes, in the order of their names (fp_mode_names()); listed once.
enum class FpMode : uint8_t { Ieee, FtzDaz };

// "ieee", "ftz_daz": the config's, the command line's and the CSV's spellings.
std::span<const std::string_view> fp_mode_names();
std::string_view fp_mode_name(FpMode mode);
std::optional<FpMode> parse_fp_mode(std::string_view name);

// The calling thread's mode: FtzDaz when both bits are set, Ieee when neither is; a
// thread with one of the two set is neither (nullopt).
std::optional<FpMode> current_fp_mode();

// Puts the calling thread in `mode` for the guard's lifetime, then restores the control
// register as it was (rounding and exception masks untouched).
class ScopedFpMode {
public:
    explicit ScopedFpMode(FpMode mode);
    ~ScopedFpMode();
    ScopedFpMode(const ScopedFpMode&) = delete;
    ScopedFpMode& operator=(const ScopedFpMode&) = delete;

private:
    uint32_t saved_;
};

}  // namespace accelbench
