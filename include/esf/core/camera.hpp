#pragma once
// Pinhole camera intrinsics, shared by rendering (synthetic views) and depth images.
// Header-only, so that every module can use it without linking another.

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace esf {

/// Pinhole camera: x right, y down, z forward (metres), pixel (u, v) = (fx x/z + cx, fy y/z + cy);
/// pixel centres are at integer (u, v), u in [0, width), v in [0, height). The defaults are the
/// Kinect v1 values. Fields are in the order fx, fy, cx, cy, width, height, so that
/// CameraIntrinsics{fx, fy, cx, cy} keeps the Kinect image size.
struct CameraIntrinsics {
    double fx = 525.0;
    double fy = 525.0;
    double cx = 319.5;
    double cy = 239.5;
    int width = 640;
    int height = 480;

    static constexpr int kMaxSide = 16384;

    /// 640x480, fx = fy = 525, cx = 319.5, cy = 239.5 (the default).
    static CameraIntrinsics kinect() { return CameraIntrinsics{}; }

    /// PCL's render_views_tesselated_sphere: 150x150 pixels, 57 degree field of view
    /// (fx = fy = 75 / tan(28.5 deg) = 138.1), principal point at the image centre.
    static CameraIntrinsics pcl_renderer() {
        CameraIntrinsics c;
        c.width = 150;
        c.height = 150;
        c.fx = c.fy = 75.0 / std::tan(57.0 / 2.0 * std::numbers::pi / 180.0);
        c.cx = c.cy = 74.5;
        return c;
    }

    /// The pixel that the point (x, y, z) falls on: (u, v) rounded to the nearest integers, halves
    /// away from zero (as std::lround, inlined: this runs for every point of every hypothesis).
    /// False where z is not positive or the pixel lies outside the image.
    bool pixel(double x, double y, double z, long& u, long& v) const {
        if (!(z > 0.0)) return false;
        u = nearest_integer(fx * x / z + cx);
        v = nearest_integer(fy * y / z + cy);
        return u >= 0 && v >= 0 && u < width && v < height;
    }

    /// Throws std::invalid_argument unless the size is in [1, kMaxSide] a side, the focal lengths
    /// positive and everything finite.
    void validate() const {
        if (width <= 0 || height <= 0 || width > kMaxSide || height > kMaxSide)
            throw std::invalid_argument("camera size must be in [1, " + std::to_string(kMaxSide) +
                                        "] pixels a side, got " + std::to_string(width) + "x" +
                                        std::to_string(height));
        if (!(std::isfinite(fx) && fx > 0.0 && std::isfinite(fy) && fy > 0.0))
            throw std::invalid_argument("camera focal lengths must be positive and finite");
        if (!std::isfinite(cx) || !std::isfinite(cy))
            throw std::invalid_argument("camera principal point must be finite");
    }

  private:
    // std::lround's value where it fits a pixel index; -1 for what lies far out or is NaN.
    static long nearest_integer(double x) {
        if (!(x > -1e9 && x < 1e9)) return -1;
        const auto t = static_cast<long>(x);  // towards zero
        const double rest = x - static_cast<double>(t);
        // Without branches: which way a pixel rounds is a coin toss, and mispredicted often.
        return t + static_cast<long>(rest >= 0.5) - static_cast<long>(rest <= -0.5);
    }
};

}  // namespace esf
