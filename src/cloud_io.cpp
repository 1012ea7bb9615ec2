#include "esf/cloud_io.hpp"

#include <fstream>

#include "esf/error.hpp"

// Placeholder so the tree builds; the full reader set is being written.
namespace esf {

CloudFormat cloud_format_from_path(const std::string& path) {
    if (path.ends_with(".pcd")) return CloudFormat::kPcd;
    if (path.ends_with(".ply")) return CloudFormat::kPly;
    return CloudFormat::kXyz;
}

}  // namespace esf
