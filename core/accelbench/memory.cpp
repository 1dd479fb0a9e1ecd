#include "accelbench/memory.h"

#include <sys/resource.h>

#include <fstream>
#include <sstream>
#include <string>

namespace accelbench {

uint64_t peak_rss_bytes() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("VmHWM:", 0) != 0) continue;
        std::istringstream fields(line.substr(6));
        uint64_t kib = 0;
        if (fields >> kib) return kib * 1024;  // the kernel reports "VmHWM:   1234 kB"
    }
    rusage usage{};
    if (getrusage(RUSAGE_SELF, &usage) == 0) return uint64_t(usage.ru_maxrss) * 1024;  // kilobytes on Linux
    return 0;
}

bool reset_peak_rss() {
    std::ofstream clear_refs("/proc/self/clear_refs");
    if (!clear_refs) return false;
    clear_refs << "5";
    clear_refs.flush();
    return bool(clear_refs);
}

}  // namespace accelbench
