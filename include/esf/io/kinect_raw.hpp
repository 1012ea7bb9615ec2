#pragma once
// The Kinect v1's raw 11-bit depth and metres. The sensor reports a shifted disparity: raw =
// kKinectRawOffset - 8 d, where d = fx b / z is the disparity in pixels between the projector
// and the infrared camera (baseline b), measured in steps of 1/8 pixel. The depth of a raw
// value is therefore
//
//   z = 8 fx b / (kKinectRawOffset - raw)      (metres; fx in pixels, b in metres)
//
// and 2047 (kKinectRawNoReading) means no reading. With the project's Kinect values (fx = 525
// pixels, b = 0.075 m, render/sensor_model.hpp) and an offset of 1085 this follows the widely
// used fit z = 1 / (3.3309 - 0.0030711 raw) (N. Burrus' calibration) within 1.5 % from 0.5 to
// 4 m, and one raw step is exactly one disparity step of the sensor model: raw -> metres ->
// raw gives the raw value back, and metres -> raw -> metres is the sensor model's
// quantise_kinect_depth().

#include <cstdint>
#include <span>
#include <vector>

#include "esf/core/camera.hpp"
#include "esf/core/point_cloud.hpp"

namespace esf {

inline constexpr std::uint16_t kKinectRawNoReading = 2047;
inline constexpr double kKinectRawOffset = 1085.0;      ///< raw value of zero disparity
inline constexpr double kKinectRawBaseline = 0.075;     ///< metres (= kKinectBaseline)
inline constexpr double kKinectRawStepsPerPixel = 8.0;  ///< 1 / kKinectDisparityStep
inline constexpr int kKinectFrameWidth = 640;
inline constexpr int kKinectFrameHeight = 480;
inline constexpr std::size_t kKinectFramePixels = 640 * 480;

/// Depth in metres of a raw value for focal length fx (pixels); NaN for 2047 and for every value
/// at or above kKinectRawOffset (no reading, or no finite depth).
double kinect_raw_to_metres(std::uint16_t raw, double fx = 525.0);

/// The raw value that measures depth z (metres): the disparity rounded to the nearest 1/8 pixel.
/// kKinectRawNoReading for NaN, infinite or non-positive depths, for depths nearer than the
/// smallest raw value can express (8 fx b / kKinectRawOffset, 0.29 m at fx = 525) and for
/// depths whose disparity rounds to zero.
std::uint16_t kinect_metres_to_raw(double z, double fx = 525.0);

/// The organised cloud (camera.width x camera.height, camera frame, metres, NaN where no
/// reading) of a raw frame back-projected through `camera`; `rgb` is empty or 3 bytes (R, G, B)
/// a pixel and becomes the cloud's packed colours. Throws std::invalid_argument when `raw` does
/// not hold width x height values, `rgb` is neither empty nor 3 bytes a pixel, or the camera is
/// invalid.
PointCloud kinect_raw_to_cloud(std::span<const std::uint16_t> raw,
                               std::span<const std::uint8_t> rgb = {},
                               const CameraIntrinsics& camera = CameraIntrinsics::kinect());

/// The raw frame of an organised cloud in the camera frame: each pixel's z through
/// kinect_metres_to_raw (the x and y are not used: the pixel's position is its ray). Throws
/// std::invalid_argument when the cloud is not organised with camera.width x camera.height
/// points.
std::vector<std::uint16_t> kinect_cloud_to_raw(
    const PointCloud& cloud, const CameraIntrinsics& camera = CameraIntrinsics::kinect());

/// The cloud's packed colours as 3 bytes a pixel (R, G, B); grey (128) for a cloud without them.
std::vector<std::uint8_t> kinect_cloud_to_rgb(const PointCloud& cloud);

}  // namespace esf
