// Exclusive locks on the files a run or a merge writes (the results CSV, its .reps.csv),
// so that a second concurrent writer of the same output is refused with a clear message
// instead of interleaving rows (two headers, every combination twice, which --resume
// would then accept). flock(2) locks belong to the open file and end with the process,
// so a killed run leaves no stale lock behind.
#pragma once

#include <string>
#include <vector>

namespace accelbench {

class OutputLock {
public:
    OutputLock() = default;
    // Locks each path (creating an empty file where there is none). Throws
    // std::runtime_error naming the file when another process holds it, or when the path
    // is not a regular file (a directory, /dev/null, a FIFO: never an output).
    explicit OutputLock(const std::vector<std::string>& paths);
    OutputLock(OutputLock&& other) noexcept : fds_(std::move(other.fds_)) { other.fds_.clear(); }
    OutputLock& operator=(OutputLock&& other) noexcept;
    ~OutputLock();
    // Adds a lock on `path` (e.g. the repetitions file once it is known).
    void add(const std::string& path);

private:
    void release();
    std::vector<int> fds_;
};

// Shared locks on the files a merge reads. A run holds its output's exclusive lock until it
// ends, so an input that cannot be locked is still being written: it is refused, never read
// half-finished. Readers do not exclude each other.
class InputLock {
public:
    // Locks each path that exists (one that does not is not read either). Throws
    // std::runtime_error naming the file when a process holds its exclusive lock.
    explicit InputLock(const std::vector<std::string>& paths);
    InputLock(const InputLock&) = delete;
    InputLock& operator=(const InputLock&) = delete;
    ~InputLock();

private:
    std::vector<int> fds_;
};

// Throws std::runtime_error when `path` exists and is not a regular file: an output path
// must name a file ('/dev/null' or a directory would end in a filesystem_error).
void require_regular_file_or_absent(const std::string& path, const std::string& what);

}  // namespace accelbench
