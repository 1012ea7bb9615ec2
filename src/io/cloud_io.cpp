// The format of a cloud file from its extension, and read_cloud() choosing the reader. The
// readers and writers live in pcd_reader.cpp, pcd_writer.cpp, ply_cloud_io.cpp and
// xyz_cloud_io.cpp.

#include "esf/io/cloud_io.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

#include "io/cloud_io_detail.hpp"

namespace esf {

CloudFormat cloud_format_from_path(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".pcd") return CloudFormat::kPcd;
    if (ext == ".ply") return CloudFormat::kPly;
    if (ext == ".xyz" || ext == ".txt" || ext == ".pts") return CloudFormat::kXyz;
    detail::fail(path, 0, "unknown point cloud format (expected .pcd, .ply, .xyz, .txt or .pts)");
}

PointCloud read_cloud(const std::string& path) {
    switch (cloud_format_from_path(path)) {
        case CloudFormat::kPcd:
            return read_pcd(path);
        case CloudFormat::kPly:
            return read_ply_cloud(path);
        case CloudFormat::kXyz:
            break;
    }
    return read_xyz(path);
}

std::size_t read_finite_points(const std::string& path, Points& finite) {
    PointCloud cloud;
    switch (cloud_format_from_path(path)) {
        case CloudFormat::kPcd:
            return detail::read_pcd_finite(path, finite);
        case CloudFormat::kPly:
            cloud = read_ply_cloud(path);
            break;
        case CloudFormat::kXyz:
            cloud = read_xyz(path);
            break;
    }
    return drop_non_finite(cloud.points, finite);
}

}  // namespace esf
