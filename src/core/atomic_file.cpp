#include "core/atomic_file.hpp"

#include <fstream>
#include <system_error>

#include "esf/core/error.hpp"

namespace esf::detail {

namespace fs = std::filesystem;

void write_file_atomically(const fs::path& path, const void* data, std::size_t size) {
    const fs::path tmp = path.string() + ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw IoError(file_message(path.string(), 0, "cannot create " + tmp.string()));
        out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
        out.close();
        if (!out) {
            std::error_code ec;
            fs::remove(tmp, ec);
            throw IoError(file_message(path.string(), 0, "write failed"));
        }
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw IoError(file_message(path.string(), 0, "cannot rename the temporary file"));
    }
}

}  // namespace esf::detail
