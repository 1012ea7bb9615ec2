#pragma once
// Writes a file through a temporary name beside it and a rename, so that a failure leaves the
// previous file (or none) and never a partial one.

#include <cstddef>
#include <filesystem>

namespace esf::detail {

/// Throws esf::IoError naming `path` when the temporary file cannot be written or renamed.
void write_file_atomically(const std::filesystem::path& path, const void* data, std::size_t size);

}  // namespace esf::detail
