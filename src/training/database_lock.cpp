#include "training/database_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "esf/core/error.hpp"

namespace esf::detail {

int lock_database_for_writing(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        throw IoError(
            file_message(path, 0, std::string("cannot open for locking: ") + std::strerror(errno)));
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
        const int error = errno;
        ::close(fd);
        if (error == EWOULDBLOCK)
            throw IoError(file_message(path, 0, "database is in use by another training"));
        throw IoError(file_message(path, 0, std::string("cannot lock: ") + std::strerror(error)));
    }
    return fd;
}

}  // namespace esf::detail
