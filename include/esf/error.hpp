#pragma once
// Error types shared by every module.
//
// Broken preconditions (empty clouds, bad options) throw std::invalid_argument; problems with
// files throw esf::IoError, whose message starts with the file name (and line, where known).

#include <stdexcept>
#include <string>

namespace esf {

/// A file could not be read or written; what() reads "path[:line]: reason".
class IoError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// Builds the "path:line: reason" message used by IoError (line 0 = no line).
std::string file_message(const std::string& path, std::size_t line, const std::string& reason);

}  // namespace esf
