#pragma once
// Depth images: 16-bit grayscale PNG (one depth per pixel in sensor units, millimetres for
// Kinect-style sensors, 0 = no data), and their back-projection to an organised point cloud
// through pinhole intrinsics.

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "esf/core/camera.hpp"
#include "esf/core/point_cloud.hpp"

namespace esf {

// CameraIntrinsics (pinhole, Kinect v1 defaults) comes from camera.hpp; depth_to_cloud() uses
// fx, fy, cx, cy and ignores the image size (the image's own).

/// A depth image, row-major from the top-left pixel; depth[v * width + u] is in sensor units.
struct DepthImage {
    std::uint32_t width = 0;
    std::uint32_t height = 0;
    std::vector<std::uint16_t> depth;
};

/// Reads a 16-bit grayscale PNG. Throws esf::IoError naming the file when it cannot be opened,
/// is not a PNG, is not 16-bit grayscale (e.g. an 8-bit or colour image) or is truncated/corrupt.
DepthImage read_depth_png(const std::string& path);
DepthImage read_depth_png(std::istream& in, const std::string& name);

/// Writes a 16-bit grayscale PNG; throws std::invalid_argument for an inconsistent image and
/// esf::IoError when the file cannot be written.
void write_depth_png(const std::string& path, const DepthImage& image);
void write_depth_png(std::ostream& out, const DepthImage& image, const std::string& name);

/// Back-projects every pixel (u, v) with depth value D > 0 to
///   z = D * metres_per_unit,  x = (u - cx) z / fx,  y = (v - cy) z / fy
/// (camera frame: x right, y down, z forward). Pixels without data become NaN points, so the
/// cloud stays organised (width x height). Throws std::invalid_argument for an empty or
/// inconsistent image, non-positive or non-finite focal lengths or scale.
PointCloud depth_to_cloud(const DepthImage& image, const CameraIntrinsics& intrinsics = {},
                          double metres_per_unit = 0.001);

}  // namespace esf
