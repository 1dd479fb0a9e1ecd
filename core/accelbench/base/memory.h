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

// Fixes glibc's malloc thresholds at their defaults (blocks of 128 KiB or more mapped fresh
// and unmapped when freed; the heap's free top trimmed past 128 KiB) and turns off their
// dynamic growth, which every free of a large mapped block triggers. With it growing, a
// build's arrays came from memory an earlier model's preparation or build had left on the
// heap (no page faults) or from fresh pages (one fault per 4 KiB page), depending on what
// the process, or the parent it was forked from, had freed before: the same combination
// measured 3.5 or 5.8 ms in two configs (docs/decisions.md). Fixed, every timed build pays
// for its own fresh memory, as Embree's builds do (their allocator maps its blocks).
// Call once at the start of a program that times, before any large allocation; a
// no-op returning false where the allocator is not glibc's.
bool fix_malloc_thresholds();

}  // namespace accelbench
