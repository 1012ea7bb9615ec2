// CameraIntrinsics::pixel against std::lround and hand-computed pixels.

#include "esf/core/camera.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace esf {
namespace {

TEST(CameraPixel, RoundsHalvesAwayFromZeroAsLround) {
    const CameraIntrinsics camera;  // fx = fy = 525, cx = 319.5, cy = 239.5
    long u = 0, v = 0;
    // x / z = 0.5 / 525 puts u at exactly 320; y = 0 puts v at 239.5, rounded up to 240.
    ASSERT_TRUE(camera.pixel(0.5 / 525.0, 0.0, 1.0, u, v));
    EXPECT_EQ(u, 320);
    EXPECT_EQ(v, 240);
    // u = -0.5 rounds away from zero to -1: outside the image.
    EXPECT_FALSE(camera.pixel(-320.0 / 525.0, 0.0, 1.0, u, v));
    // u = -0.49 rounds to 0: inside.
    ASSERT_TRUE(camera.pixel(-319.99 / 525.0, 0.0, 1.0, u, v));
    EXPECT_EQ(u, 0);
    // Many coordinates, as std::lround would give them.
    for (int i = -2000; i <= 2000; ++i) {
        const double x = i * 0.000731, y = i * -0.000417, z = 1.3;
        const long lu = std::lround(camera.fx * x / z + camera.cx);
        const long lv = std::lround(camera.fy * y / z + camera.cy);
        const bool inside = lu >= 0 && lv >= 0 && lu < camera.width && lv < camera.height;
        ASSERT_EQ(camera.pixel(x, y, z, u, v), inside) << i;
        if (inside) {
            EXPECT_EQ(u, lu) << i;
            EXPECT_EQ(v, lv) << i;
        }
    }
}

TEST(CameraPixel, RefusesPointsBehindFarOutOrNotANumber) {
    const CameraIntrinsics camera;
    long u = 0, v = 0;
    EXPECT_FALSE(camera.pixel(0.0, 0.0, 0.0, u, v));
    EXPECT_FALSE(camera.pixel(0.0, 0.0, -1.0, u, v));
    EXPECT_FALSE(camera.pixel(1e300, 0.0, 1e-300, u, v));
    EXPECT_FALSE(camera.pixel(std::numeric_limits<double>::quiet_NaN(), 0.0, 1.0, u, v));
    EXPECT_FALSE(camera.pixel(0.0, 0.0, std::numeric_limits<double>::quiet_NaN(), u, v));
    EXPECT_FALSE(camera.pixel(std::numeric_limits<double>::infinity(), 0.0, 1.0, u, v));
}

}  // namespace
}  // namespace esf
