#include "esf/io/kinect_raw.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace esf {

namespace {

constexpr double kStep = 1.0 / kKinectRawStepsPerPixel;

void check_fx(double fx) {
    if (!(std::isfinite(fx) && fx > 0.0))
        throw std::invalid_argument("Kinect focal length must be positive and finite, got " +
                                    std::to_string(fx));
}

}  // namespace

double kinect_raw_to_metres(std::uint16_t raw, double fx) {
    check_fx(fx);
    if (raw >= kKinectRawNoReading || static_cast<double>(raw) >= kKinectRawOffset)
        return std::numeric_limits<double>::quiet_NaN();
    const double steps = kKinectRawOffset - static_cast<double>(raw);
    // The sensor model's expression (quantise_kinect_depth), so that the two agree bit for bit.
    return fx * kKinectRawBaseline / (steps * kStep);
}

std::uint16_t kinect_metres_to_raw(double z, double fx) {
    check_fx(fx);
    if (!(std::isfinite(z) && z > 0.0)) return kKinectRawNoReading;
    const double disparity = fx * kKinectRawBaseline / z;
    if (!(disparity / kStep + 0.5 < kKinectRawOffset + 1.0)) return kKinectRawNoReading;
    const auto steps = static_cast<std::int64_t>(disparity / kStep + 0.5);
    if (steps <= 0 || static_cast<double>(steps) > kKinectRawOffset) return kKinectRawNoReading;
    return static_cast<std::uint16_t>(static_cast<std::int64_t>(kKinectRawOffset) - steps);
}

PointCloud kinect_raw_to_cloud(std::span<const std::uint16_t> raw,
                               std::span<const std::uint8_t> rgb, const CameraIntrinsics& camera) {
    camera.validate();
    const std::size_t pixels =
        static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height);
    if (raw.size() != pixels)
        throw std::invalid_argument("Kinect frame has " + std::to_string(raw.size()) +
                                    " depth values, expected " + std::to_string(pixels));
    if (!rgb.empty() && rgb.size() != 3 * pixels)
        throw std::invalid_argument("Kinect frame has " + std::to_string(rgb.size()) +
                                    " colour bytes, expected " + std::to_string(3 * pixels));
    std::array<float, 2048> depth_of{};
    for (std::size_t r = 0; r < depth_of.size(); ++r)
        depth_of[r] =
            static_cast<float>(kinect_raw_to_metres(static_cast<std::uint16_t>(r), camera.fx));
    PointCloud cloud;
    cloud.width = static_cast<std::uint32_t>(camera.width);
    cloud.height = static_cast<std::uint32_t>(camera.height);
    cloud.points.resize(pixels);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const double inv_fx = 1.0 / camera.fx, inv_fy = 1.0 / camera.fy;
    for (int v = 0; v < camera.height; ++v) {
        const auto y_ray = static_cast<float>((v - camera.cy) * inv_fy);
        for (int u = 0; u < camera.width; ++u) {
            const std::size_t i =
                static_cast<std::size_t>(v) * static_cast<std::size_t>(camera.width) +
                static_cast<std::size_t>(u);
            const std::uint16_t r = raw[i];
            const float z = r < depth_of.size() ? depth_of[r] : nan;
            if (std::isnan(z)) {
                cloud.points[i] = Eigen::Vector3f(nan, nan, nan);
                continue;
            }
            const auto x_ray = static_cast<float>((u - camera.cx) * inv_fx);
            cloud.points[i] = Eigen::Vector3f(x_ray * z, y_ray * z, z);
        }
    }
    if (!rgb.empty()) {
        cloud.rgb.resize(pixels);
        for (std::size_t i = 0; i < pixels; ++i)
            cloud.rgb[i] = (std::uint32_t{rgb[3 * i]} << 16) |
                           (std::uint32_t{rgb[3 * i + 1]} << 8) | std::uint32_t{rgb[3 * i + 2]};
    }
    return cloud;
}

std::vector<std::uint16_t> kinect_cloud_to_raw(const PointCloud& cloud,
                                               const CameraIntrinsics& camera) {
    camera.validate();
    if (cloud.width != static_cast<std::uint32_t>(camera.width) ||
        cloud.height != static_cast<std::uint32_t>(camera.height) ||
        cloud.points.size() !=
            static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height))
        throw std::invalid_argument(
            "a Kinect frame needs an organised cloud of " + std::to_string(camera.width) + "x" +
            std::to_string(camera.height) + " points, got " + std::to_string(cloud.width) + "x" +
            std::to_string(cloud.height) + " (" + std::to_string(cloud.points.size()) + " points)");
    std::vector<std::uint16_t> raw(cloud.points.size());
    for (std::size_t i = 0; i < raw.size(); ++i)
        raw[i] = kinect_metres_to_raw(static_cast<double>(cloud.points[i].z()), camera.fx);
    return raw;
}

std::vector<std::uint8_t> kinect_cloud_to_rgb(const PointCloud& cloud) {
    std::vector<std::uint8_t> rgb(3 * cloud.points.size(), 128);
    if (cloud.rgb.size() != cloud.points.size()) return rgb;
    for (std::size_t i = 0; i < cloud.rgb.size(); ++i) {
        rgb[3 * i] = static_cast<std::uint8_t>((cloud.rgb[i] >> 16) & 0xff);
        rgb[3 * i + 1] = static_cast<std::uint8_t>((cloud.rgb[i] >> 8) & 0xff);
        rgb[3 * i + 2] = static_cast<std::uint8_t>(cloud.rgb[i] & 0xff);
    }
    return rgb;
}

}  // namespace esf
