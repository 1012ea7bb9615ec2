#pragma once
// The one way the project writes a file: the bytes go to a fresh temporary file beside the
// target (a unique name, created exclusively, so that concurrent writers never share one), which
// is then renamed over the target. A failure removes the temporary and leaves the previous file
// (or none), never a partial one.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string_view>

namespace esf::detail {

/// Replaces `path` with `bytes`. Throws esf::IoError naming `path` when the temporary file
/// cannot be created or written, or cannot be renamed over `path`.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

/// The same for `size` bytes at `data`.
void write_file_atomically(const std::filesystem::path& path, const void* data, std::size_t size);

/// Replaces `path` with what `write` puts into the stream it is given (a failed stream is a
/// write error). Exceptions from `write` leave the previous file as it was.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write);

}  // namespace esf::detail
