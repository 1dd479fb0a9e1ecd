// The process's memory high-water mark, for the harness column `peak_rss_bytes` (extreme
// parameters must terminate with bounded memory, and the CSV shows how much).
#pragma once

#include <cstdint>

namespace accelbench {

// Peak resident set size of this process so far, in bytes: VmHWM from /proc/self/status
// (Linux), else getrusage's ru_maxrss. 0 if neither is available.
uint64_t peak_rss_bytes();

// Current resident set size in bytes (VmRSS), 0 where unavailable.
uint64_t current_rss_bytes();

// Resets the high-water mark to the current resident size (Linux >= 4.0: writes "5" to
// /proc/self/clear_refs), so that the next peak_rss_bytes() measures one phase (one
// build, one row) rather than the whole process. Returns false where that is not
// possible; peak_rss_bytes() then keeps reporting the process-wide peak.
bool reset_peak_rss();

}  // namespace accelbench
