#include "accelbench/base/memory.h"

#include <sys/resource.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <fstream>
#include <sstream>
#include <string>

namespace accelbench {

namespace {

// A "Key:   1234 kB" line of /proc/self/status, in bytes; 0 if absent.
uint64_t status_kib_field(const std::string& key) {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind(key, 0) != 0) continue;
        std::istringstream fields(line.substr(key.size()));
        uint64_t kib = 0;
        if (fields >> kib) return kib * 1024;
    }
    return 0;
}

}  // namespace

uint64_t peak_rss_bytes() {
    if (uint64_t hwm = status_kib_field("VmHWM:")) return hwm;
    rusage usage{};
    if (getrusage(RUSAGE_SELF, &usage) == 0) return uint64_t(usage.ru_maxrss) * 1024;  // kilobytes on Linux
    return 0;
}

uint64_t current_rss_bytes() { return status_kib_field("VmRSS:"); }

bool reset_peak_rss() {
    std::ofstream clear_refs("/proc/self/clear_refs");
    if (!clear_refs) return false;
    clear_refs << "5";
    clear_refs.flush();
    return bool(clear_refs);
}

bool fix_malloc_thresholds() {
#if defined(__GLIBC__)
    // glibc's defaults (malloc/malloc.c: DEFAULT_MMAP_THRESHOLD_MIN, DEFAULT_TRIM_THRESHOLD);
    // setting either one by mallopt disables the dynamic adjustment of both.
    constexpr int kDefaultThreshold = 128 * 1024;
    return mallopt(M_MMAP_THRESHOLD, kDefaultThreshold) == 1 && mallopt(M_TRIM_THRESHOLD, kDefaultThreshold) == 1;
#else
    return false;
#endif
}

}  // namespace accelbench
