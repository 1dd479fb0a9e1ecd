// Where a measurement came from: the commit, whether the tree was dirty, the compiler,
// build type, CPU and Embree version. Every CSV row carries these columns so results
// from different builds or machines are never silently mixed.
#pragma once

#include <string>

namespace accelbench {

struct Provenance {
    std::string git_sha;
    bool git_dirty = false;
    std::string compiler;
    std::string build_type;
    std::string cpu;
    std::string embree_version;
};

// Gathered once per process (git is asked at run time in the source tree the binary
// was built from; "unknown" when that is not a git checkout).
const Provenance& provenance();

}  // namespace accelbench
