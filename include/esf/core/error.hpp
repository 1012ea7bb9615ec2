#pragma once
// Error types shared by every module.
//
// Broken preconditions (empty clouds, bad options, an index out of range) throw
// std::invalid_argument; problems with files throw esf::IoError, whose message starts with the
// file name (and line, where known). Only a failure of the system itself (Embree cannot create
// a device, the PNG encoder cannot allocate, a PCL baseline's helper process cannot be started)
// is a plain std::runtime_error naming what failed.

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
