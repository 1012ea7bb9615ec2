#include "training/database_schema.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "esf/core/error.hpp"

namespace esf::detail {

void check_database_file_header(const std::string& path, OpenMode mode) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const auto status = fs::status(path, ec);
    if (!fs::exists(status)) {
        if (mode == OpenMode::kRead) throw IoError(file_message(path, 0, "no such file"));
        return;
    }
    if (fs::is_directory(status)) throw IoError(file_message(path, 0, "is a directory"));
    const auto size = fs::file_size(path, ec);
    if (ec) throw IoError(file_message(path, 0, "cannot read: " + ec.message()));
    if (size == 0) {
        if (mode == OpenMode::kRead)
            throw IoError(file_message(path, 0, "empty file, not an esf database"));
        return;  // SQLite initialises an empty file as a new database
    }
    std::array<unsigned char, 100> header{};
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(file_message(path, 0, "cannot open for reading"));
    in.read(reinterpret_cast<char*>(header.data()), header.size());
    const auto got = static_cast<std::size_t>(in.gcount());
    static constexpr char kMagic[] = "SQLite format 3";  // 16 bytes with the terminating NUL
    if (got < 16 || std::memcmp(header.data(), kMagic, 16) != 0)
        throw IoError(file_message(path, 0, "not an SQLite database (esf databases are SQLite)"));
    if (got < header.size())
        throw IoError(file_message(path, 0,
                                   "truncated SQLite database (" + std::to_string(size) +
                                       " bytes, shorter than its header)"));
    auto be32 = [&](std::size_t at) {
        return std::uint32_t{header[at]} << 24 | std::uint32_t{header[at + 1]} << 16 |
               std::uint32_t{header[at + 2]} << 8 | std::uint32_t{header[at + 3]};
    };
    std::uint64_t page_size = std::uint32_t{header[16]} << 8 | header[17];
    if (page_size == 1) page_size = 65536;
    const std::uint64_t pages = be32(28);
    // The page count in the header is valid when the change counter matches version-valid-for.
    // With a write-ahead log beside the file the log may hold the newer pages, so skip then.
    const bool count_valid = pages != 0 && be32(24) == be32(92);
    if (count_valid && !fs::exists(path + "-wal") && size < pages * page_size)
        throw IoError(file_message(path, 0,
                                   "truncated SQLite database (" + std::to_string(size) +
                                       " bytes, its header says " +
                                       std::to_string(pages * page_size) + ")"));
}

}  // namespace esf::detail
