#include "core/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <sstream>
#include <string>
#include <system_error>

#include "core/splitmix64.hpp"
#include "esf/core/error.hpp"

namespace esf::detail {

namespace fs = std::filesystem;

namespace {

std::string errno_message(int error) {
    return std::error_code(error, std::generic_category()).message();
}

/// A name for the next temporary file: the process, a per-process counter and a random part,
/// so that names neither repeat within a process nor collide between processes.
std::string temporary_suffix() {
    static std::atomic<std::uint64_t> counter{0};
    static const std::uint64_t start = mix64(
        static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count()) ^
        (static_cast<std::uint64_t>(::getpid()) << 32));
    const std::uint64_t n = counter.fetch_add(1, std::memory_order_relaxed);
    static constexpr char kDigits[] = "0123456789abcdefghijklmnopqrstuvwxyz";
    std::uint64_t bits = mix64(start + kGoldenGamma * (n + 1));
    std::string random(8, '0');
    for (char& c : random) {
        c = kDigits[bits % 36];
        bits /= 36;
    }
    return ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(n) + "-" + random;
}

/// Creates a temporary file beside `path` that did not exist before (O_EXCL; the permissions
/// an ordinary new file gets, 0666 less the umask). Returns its descriptor and sets `temporary`.
int create_temporary(const fs::path& path, std::string& temporary) {
    int error = 0;
    for (int attempt = 0; attempt < 100; ++attempt) {
        temporary = path.string() + temporary_suffix();
        const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0) return fd;
        error = errno;
        if (error != EEXIST) break;
    }
    throw IoError(
        file_message(path.string(), 0, "cannot create temporary file: " + errno_message(error)));
}

}  // namespace

void write_file_atomically(const fs::path& path, std::string_view bytes) {
    std::string temporary;
    const int fd = create_temporary(path, temporary);
    const auto give_up = [&](const std::string& reason) {
        ::unlink(temporary.c_str());
        throw IoError(file_message(path.string(), 0, reason));
    };
    const char* p = bytes.data();
    std::size_t left = bytes.size();
    while (left > 0) {
        const ssize_t written = ::write(fd, p, left);
        if (written < 0) {
            if (errno == EINTR) continue;
            const int error = errno;
            ::close(fd);
            give_up("write failed: " + errno_message(error));
        }
        p += written;
        left -= static_cast<std::size_t>(written);
    }
    if (::close(fd) != 0) give_up("write failed: " + errno_message(errno));
    std::error_code ec;
    fs::rename(temporary, path, ec);
    if (ec) give_up("cannot replace the file: " + ec.message());
}

void write_file_atomically(const fs::path& path, const void* data, std::size_t size) {
    write_file_atomically(path, std::string_view(static_cast<const char*>(data), size));
}

void write_file_atomically(const fs::path& path, const std::function<void(std::ostream&)>& write) {
    std::ostringstream out;
    write(out);
    if (!out) throw IoError(file_message(path.string(), 0, "write failed"));
    write_file_atomically(path, std::string_view(out.view()));
}

}  // namespace esf::detail
