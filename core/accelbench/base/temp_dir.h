// A private temporary directory, removed with everything in it when it goes out of scope.
#pragma once

#include <filesystem>
#include <string>

namespace accelbench {

class TempDir {
public:
    // Creates <parent>/<prefix>XXXXXX (mkdtemp: a fresh name, mode 0700); throws
    // std::runtime_error naming the parent when it cannot.
    explicit TempDir(const std::string& prefix,
                     const std::filesystem::path& parent = std::filesystem::temp_directory_path());
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

}  // namespace accelbench
