#include "accelbench/base/temp_dir.h"

#include <cstdlib>
#include <stdexcept>
#include <system_error>

namespace accelbench {

TempDir::TempDir(const std::string& prefix, const std::filesystem::path& parent) {
    std::string pattern = (parent / (prefix + "XXXXXX")).string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("cannot create a temporary directory in " + parent.string());
    path_ = pattern;
}

TempDir::~TempDir() {
    std::error_code ignored;  // a destructor must not throw; a leftover is harmless
    std::filesystem::remove_all(path_, ignored);
}

}  // namespace accelbench
