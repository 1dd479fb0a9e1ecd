#include "util/output_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace accelbench {

void require_regular_file_or_absent(const std::string& path, const std::string& what) {
    std::error_code ec;
    const fs::file_status st = fs::symlink_status(path, ec);
    if (ec || !fs::exists(st)) return;
    const fs::file_status target = fs::status(path, ec);
    if (!ec && fs::is_regular_file(target)) return;
    const char* kind = fs::is_directory(target)                      ? "a directory"
        : fs::is_character_file(target) || fs::is_block_file(target) ? "a device"
        : fs::is_fifo(target)                                        ? "a FIFO"
        : fs::is_socket(target)                                      ? "a socket"
                                                                     : "not a regular file";
    throw std::runtime_error("'" + path + "' is " + kind + ": " + what + " must be a regular file (or not exist yet)");
}

OutputLock::OutputLock(const std::vector<std::string>& paths) {
    try {
        for (const auto& p : paths) add(p);
    } catch (...) {
        release();  // a constructor that throws runs no destructor: the locks taken so far end here
        throw;
    }
}

OutputLock& OutputLock::operator=(OutputLock&& other) noexcept {
    if (this != &other) {
        release();
        fds_ = std::move(other.fds_);
        other.fds_.clear();
    }
    return *this;
}

OutputLock::~OutputLock() { release(); }

void OutputLock::release() {
    for (int fd : fds_) ::close(fd);  // closing the descriptor releases its flock
    fds_.clear();
}

void OutputLock::add(const std::string& path) {
    require_regular_file_or_absent(path, "an output");
    if (const fs::path dir = fs::path(path).parent_path(); !dir.empty()) {
        // The first existing ancestor must be a directory ("filesystem error: cannot create
        // directories" named neither the output nor what was in its way).
        for (fs::path p = dir; !p.empty(); p = p.parent_path()) {
            std::error_code ec;
            if (fs::exists(p, ec)) {
                if (!fs::is_directory(p, ec))
                    throw std::runtime_error("'" + p.string() + "' is not a directory: it would hold the output '" +
                                             path + "'");
                break;
            }
            if (p == p.parent_path()) break;
        }
        fs::create_directories(dir);
    }
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) throw std::runtime_error("cannot open '" + path + "' for writing: " + std::strerror(errno));
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
        const int err = errno;
        ::close(fd);
        if (err == EWOULDBLOCK)
            throw std::runtime_error("'" + path +
                                     "' is being written by another process (an accelbench run or merge "
                                     "holds its lock): wait for it to finish, or choose another --out");
        throw std::runtime_error("cannot lock '" + path + "': " + std::strerror(err));
    }
    fds_.push_back(fd);
}

InputLock::InputLock(const std::vector<std::string>& paths) {
    for (const auto& p : paths) {
        const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0) continue;  // absent: nothing to read
        if (::flock(fd, LOCK_SH | LOCK_NB) == 0) {
            fds_.push_back(fd);
            continue;
        }
        const int err = errno;
        ::close(fd);
        for (int held : fds_) ::close(held);
        if (err == EWOULDBLOCK)
            throw std::runtime_error("'" + p +
                                     "' is being written by another process (an accelbench run or merge holds its "
                                     "lock): wait for it to finish, then merge");
        throw std::runtime_error("cannot lock '" + p + "': " + std::strerror(err));
    }
}

InputLock::~InputLock() {
    for (int fd : fds_) ::close(fd);
}

}  // namespace accelbench
