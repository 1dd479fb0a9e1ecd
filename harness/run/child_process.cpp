#include "run/child_process.h"

#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <stdexcept>

#include "util/text.h"
#include "util/wire.h"

namespace accelbench {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
}

void write_all(int fd, std::string_view data) {
    size_t done = 0;
    while (done < data.size()) {
        ssize_t n = ::write(fd, data.data() + done, data.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;  // the parent is gone; nothing to report to
        done += size_t(n);
    }
}

// Frames on the pipe, in the wire form: a tag ('S' stage begun, 'R' result) and the
// payload's length (kFrameHeader bytes), then the payload, written as it is (a prepared
// model is hundreds of MB: no copy of it is made).
constexpr size_t kFrameHeader = sizeof(char) + sizeof(uint64_t);

void send_frame(int fd, char tag, std::string_view payload) {
    WireWriter header;
    header.put(tag);
    header.put(uint64_t(payload.size()));
    write_all(fd, header.bytes());
    write_all(fd, payload);
}

// Everything buffered for stdout and stderr, C++ streams and C stdio, written out: before a
// fork (or the child would write the parent's buffered text a second time), before a child
// exits, and before the parent stops itself.
void flush_all_output() {
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
}

// A child killed by a request to stop — SIGTERM (scancel, a Slurm time limit, kill),
// SIGINT (Ctrl-C), SIGHUP, SIGQUIT — was not failed by its combination: the whole run is
// being stopped, and the same signal is on its way to this process (Slurm and a terminal
// signal every process of the job). Found by make test-slurm: the child died
// first, this parent wrote `status=error, the measurement process died from signal 15
// (Terminated)` before its own SIGTERM arrived, and `--resume` then kept that row instead
// of measuring the combination again, so the merged grid differed from a single-process
// run. So the parent stops itself the same way, now, without a row for the combination;
// its earlier rows are on disk (each is flushed when written), and --resume measures the
// interrupted combination again (dropping its orphaned repetition rows). A crash of the
// structure (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT) and the kernel's OOM kill (SIGKILL)
// stay error rows.
void stop_if_asked_to_stop(int signal_number) {
    if (signal_number != SIGTERM && signal_number != SIGINT && signal_number != SIGHUP && signal_number != SIGQUIT)
        return;
    flush_all_output();
    std::signal(signal_number, SIG_DFL);
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, signal_number);
    sigprocmask(SIG_UNBLOCK, &set, nullptr);
    std::raise(signal_number);
    _exit(128 + signal_number);  // not reached; the shell's code for a death by that signal
}

}  // namespace

ChildOutcome run_in_child(const std::function<std::string(const StageFn&)>& work, double timeout_s,
                          const std::string& first_stage) {
    int fds[2];
    if (pipe(fds) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
    flush_all_output();
    const pid_t pid = fork();
    if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
    if (pid == 0) {
        ::close(fds[0]);
        prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive a killed parent
        const std::string result = work([&](const std::string& s) { send_frame(fds[1], 'S', s); });
        send_frame(fds[1], 'R', result);
        flush_all_output();
        _exit(0);
    }
    ::close(fds[1]);

    const auto deadline =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
    std::string buffer;
    ChildOutcome o;
    o.stage = first_stage;
    for (;;) {
        const double left = seconds_between(Clock::now(), deadline);
        // Past the deadline, what the child already sent is still read (without waiting), so
        // a stage it reported before the limit names the stage it was stopped in — under load
        // the parent can wake after the deadline with the child's last frames unread.
        pollfd p{fds[0], POLLIN, 0};
        const int r = poll(&p, 1, left <= 0 ? 0 : int(std::min(left * 1000.0 + 1.0, 3.6e6)));
        if (r < 0 && errno == EINTR) continue;
        if (r == 0 && left <= 0) {
            o.timed_out = true;
            break;
        }
        if (r == 0) continue;  // the loop head decides whether time is up
        char chunk[65536];
        const ssize_t n = ::read(fds[0], chunk, sizeof chunk);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;  // the child closed the pipe: finished or died
        buffer.append(chunk, size_t(n));
        while (buffer.size() >= kFrameHeader) {
            WireReader header(buffer, "a frame from the child process");
            const char tag = header.take<char>();
            const uint64_t len = header.take<uint64_t>();
            if (buffer.size() - kFrameHeader < len) {
                buffer.reserve(kFrameHeader + len);  // a prepared model can be hundreds of MB: grow once
                break;
            }
            if (tag == 'R' && buffer.size() == kFrameHeader + len) {
                // The last frame, alone in the buffer (as a result is): taken without a copy.
                buffer.erase(0, kFrameHeader);
                o.result = std::move(buffer);
                buffer.clear();
                break;
            }
            if (tag == 'S') o.stage = buffer.substr(kFrameHeader, len);
            else if (tag == 'R') o.result = buffer.substr(kFrameHeader, len);
            buffer.erase(0, kFrameHeader + len);
        }
    }
    if (o.timed_out) kill(pid, SIGKILL);
    ::close(fds[0]);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    if (!o.timed_out && WIFSIGNALED(status)) stop_if_asked_to_stop(WTERMSIG(status));
    if (o.timed_out) o.result.reset();
    if (!o.result && !o.timed_out) {
        o.failure = WIFSIGNALED(status)
            ? "died from signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")"
            : "exited with status " + std::to_string(WEXITSTATUS(status)) + " without a result";
    }
    return o;
}

std::string time_limit_message(double timeout_s, const std::string& stage, size_t combinations) {
    const std::string each = combinations > 1
        ? " for each of the " + std::to_string(combinations) + " combinations timed in one process"
        : "";
    return "exceeded the time limit (timeout_s = " + number_text(timeout_s, 6) + " s" + each + ") during " + stage;
}

}  // namespace accelbench
