// Runs a helper executable in its own process (child_process.hpp): posix_spawn, pipes, poll()
// with a deadline, SIGKILL past it.

#include "core/child_process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace esf::detail {
namespace {

using Clock = std::chrono::steady_clock;

/// A file descriptor closed when it goes out of scope.
class Fd {
  public:
    explicit Fd(int fd = -1) : fd_(fd) {}
    ~Fd() { reset(); }
    Fd(const Fd&) = delete;
    Fd& operator=(const Fd&) = delete;
    int get() const { return fd_; }
    bool open() const { return fd_ >= 0; }
    void reset() {
        if (fd_ >= 0) ::close(fd_);
        fd_ = -1;
    }

  private:
    int fd_;
};

/// Blocks SIGPIPE in the calling thread for its lifetime, so that writing to a helper that has
/// exited fails with EPIPE instead of ending the caller. A SIGPIPE raised meanwhile is consumed
/// (unless one was pending already) before the old mask comes back.
class SigpipeBlocked {
  public:
    SigpipeBlocked() {
        sigemptyset(&pipe_);
        sigaddset(&pipe_, SIGPIPE);
        sigset_t pending;
        sigemptyset(&pending);
        was_pending_ = ::sigpending(&pending) == 0 && sigismember(&pending, SIGPIPE) == 1;
        blocked_ = ::pthread_sigmask(SIG_BLOCK, &pipe_, &old_) == 0;
    }
    ~SigpipeBlocked() {
        if (!blocked_) return;
        sigset_t pending;
        sigemptyset(&pending);
        if (!was_pending_ && ::sigpending(&pending) == 0 && sigismember(&pending, SIGPIPE) == 1) {
            const timespec zero{};
            while (::sigtimedwait(&pipe_, nullptr, &zero) < 0 && errno == EINTR) {
            }
        }
        ::pthread_sigmask(SIG_SETMASK, &old_, nullptr);
    }
    SigpipeBlocked(const SigpipeBlocked&) = delete;
    SigpipeBlocked& operator=(const SigpipeBlocked&) = delete;

  private:
    sigset_t pipe_{};
    sigset_t old_{};
    bool was_pending_ = false;
    bool blocked_ = false;
};

std::runtime_error start_error(const std::string& helper, const std::string& reason) {
    return std::runtime_error("cannot start " + helper + ": " + reason);
}

/// Waits for `pid` to end; kills it with SIGKILL at `deadline` (if any) and reports that.
/// Returns false when it was killed for the deadline.
bool reap(pid_t pid, const std::optional<Clock::time_point>& deadline, int& status) {
    status = 0;
    int pause_ms = 1;
    bool killed = false;
    for (;;) {
        const pid_t got = ::waitpid(pid, &status, deadline && !killed ? WNOHANG : 0);
        if (got == pid) return !killed;
        if (got < 0) {
            if (errno == EINTR) continue;
            status = 0;  // ECHILD: reaped elsewhere (SIGCHLD ignored); the reply is checked
            return !killed;
        }
        const auto now = Clock::now();
        if (now >= *deadline) {
            ::kill(pid, SIGKILL);
            killed = true;
            continue;
        }
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(*deadline - now).count();
        const long ms = std::max<long>(1, std::min<long>(pause_ms, static_cast<long>(left)));
        const timespec pause{ms / 1000, (ms % 1000) * 1000000L};
        ::nanosleep(&pause, nullptr);
        pause_ms = std::min(pause_ms * 2, 50);
    }
}

}  // namespace

ChildResult run_child(const std::string& helper, const std::vector<std::string>& args,
                      const std::string& request, const ChildLimits& limits) {
    std::optional<Clock::time_point> deadline;
    if (limits.seconds) {
        // Beyond 10^9 s (31 years) is no bound the clock can hold.
        const double seconds = std::clamp(*limits.seconds, 0.0, 1e9);
        deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(seconds));
    }
    int in[2];
    int out[2];
    if (::pipe2(in, O_CLOEXEC) != 0)
        throw start_error(helper, std::string("pipe() failed: ") + std::strerror(errno));
    Fd in_read(in[0]);
    Fd in_write(in[1]);
    if (::pipe2(out, O_CLOEXEC) != 0)
        throw start_error(helper, std::string("pipe() failed: ") + std::strerror(errno));
    Fd out_read(out[0]);
    Fd out_write(out[1]);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, in_read.get(), STDIN_FILENO);
    posix_spawn_file_actions_adddup2(&actions, out_write.get(), STDOUT_FILENO);
    // The helper's own messages (PCL's warnings, an assertion) stay with it: the caller reports.
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(helper.c_str()));
    for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
    argv.push_back(nullptr);
    char* envp[] = {nullptr};
    pid_t pid = 0;
    const int spawned = ::posix_spawn(&pid, helper.c_str(), &actions, nullptr, argv.data(), envp);
    posix_spawn_file_actions_destroy(&actions);
    in_read.reset();
    out_write.reset();
    if (spawned != 0) throw start_error(helper, std::strerror(spawned));

    ::fcntl(in_write.get(), F_SETFL, ::fcntl(in_write.get(), F_GETFL) | O_NONBLOCK);
    ::fcntl(out_read.get(), F_SETFL, ::fcntl(out_read.get(), F_GETFL) | O_NONBLOCK);
    ChildResult result;
    std::optional<ChildResult::End> killed;
    {
        const SigpipeBlocked no_sigpipe;
        std::size_t written = 0;
        if (request.empty()) in_write.reset();
        bool reading = true;
        char buffer[1 << 16];
        while (!killed && (reading || in_write.open())) {
            pollfd fds[2];
            nfds_t count = 0;
            if (in_write.open()) fds[count++] = {in_write.get(), POLLOUT, 0};
            const nfds_t read_slot = count;
            if (reading) fds[count++] = {out_read.get(), POLLIN, 0};
            int timeout_ms = -1;
            if (deadline) {
                const auto left =
                    std::chrono::ceil<std::chrono::milliseconds>(*deadline - Clock::now());
                if (left.count() <= 0) {
                    killed = ChildResult::End::kTimedOut;
                    break;
                }
                timeout_ms = static_cast<int>(std::min<long long>(left.count(), 1 << 30));
            }
            const int ready = ::poll(fds, count, timeout_ms);
            if (ready < 0) {
                if (errno == EINTR || errno == EAGAIN) continue;
                killed = ChildResult::End::kSignalled;  // cannot wait for it: stop it
                break;
            }
            if (in_write.open() && fds[0].revents != 0) {
                const ssize_t n =
                    ::write(in_write.get(), request.data() + written, request.size() - written);
                if (n > 0) {
                    written += static_cast<std::size_t>(n);
                    if (written == request.size()) in_write.reset();
                } else if (n < 0 && errno != EINTR && errno != EAGAIN) {
                    in_write.reset();  // it stopped reading (EPIPE): its status says why
                }
            }
            if (reading && read_slot < count && fds[read_slot].revents != 0) {
                const ssize_t n = ::read(out_read.get(), buffer, sizeof buffer);
                if (n > 0) {
                    if (result.reply.size() + static_cast<std::size_t>(n) >
                        limits.max_reply_bytes) {
                        killed = ChildResult::End::kReplyTooLarge;
                        break;
                    }
                    result.reply.append(buffer, static_cast<std::size_t>(n));
                } else if (n == 0 || (errno != EINTR && errno != EAGAIN)) {
                    reading = false;
                }
            }
        }
    }
    in_write.reset();
    out_read.reset();
    if (killed) {
        ::kill(pid, SIGKILL);
        int status = 0;
        reap(pid, std::nullopt, status);
        result.end = *killed;
        result.code = *killed == ChildResult::End::kSignalled ? SIGKILL : 0;
        return result;
    }
    int status = 0;
    if (!reap(pid, deadline, status)) {
        result.end = ChildResult::End::kTimedOut;
    } else if (WIFSIGNALED(status)) {
        result.end = ChildResult::End::kSignalled;
        result.code = WTERMSIG(status);
    } else {
        result.end = ChildResult::End::kExited;
        result.code = WIFEXITED(status) ? WEXITSTATUS(status) : 0;
    }
    return result;
}

std::string describe_end(const ChildResult& result) {
    switch (result.end) {
        case ChildResult::End::kExited:
            return "exit status " + std::to_string(result.code);
        case ChildResult::End::kSignalled:
            return "signal " + std::to_string(result.code);
        case ChildResult::End::kTimedOut:
            return "killed at its time limit";
        case ChildResult::End::kReplyTooLarge:
            return "killed for a reply too large";
    }
    return "unknown end";
}

bool write_reply(const std::string& bytes) {
    const char* at = bytes.data();
    std::size_t left = bytes.size();
    while (left > 0) {
        const ssize_t n = ::write(STDOUT_FILENO, at, left);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return false;
        at += n;
        left -= static_cast<std::size_t>(n);
    }
    return true;
}

}  // namespace esf::detail
