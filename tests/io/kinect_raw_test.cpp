// Raw 11-bit Kinect depth <-> metres, and raw frames <-> organised clouds.

#include "esf/io/kinect_raw.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "../support/error_of.hpp"

namespace {

TEST(KinectRaw, HandComputedValues) {
    // z = 525 * 0.075 / ((1085 - raw) / 8) = 315 / (1085 - raw).
    EXPECT_DOUBLE_EQ(esf::kinect_raw_to_metres(770), 1.0);           // 315 steps
    EXPECT_DOUBLE_EQ(esf::kinect_raw_to_metres(455), 0.5);           // 630 steps
    EXPECT_DOUBLE_EQ(esf::kinect_raw_to_metres(0), 315.0 / 1085.0);  // the nearest depth
    EXPECT_TRUE(std::isnan(esf::kinect_raw_to_metres(2047)));        // no reading
    EXPECT_TRUE(std::isnan(esf::kinect_raw_to_metres(1085)));        // zero disparity
    EXPECT_TRUE(std::isnan(esf::kinect_raw_to_metres(1500)));
    EXPECT_EQ(esf::kinect_metres_to_raw(1.0), 770);
    EXPECT_EQ(esf::kinect_metres_to_raw(1.001), 770);  // 314.69 steps round to 315
    EXPECT_EQ(esf::kinect_metres_to_raw(0.5), 455);
    EXPECT_EQ(esf::kinect_metres_to_raw(2.0), 927);  // 157.5 steps round up to 158
}

TEST(KinectRaw, OutOfRangeIsNoReading) {
    EXPECT_EQ(esf::kinect_metres_to_raw(std::nan("")), esf::kKinectRawNoReading);
    EXPECT_EQ(esf::kinect_metres_to_raw(INFINITY), esf::kKinectRawNoReading);
    EXPECT_EQ(esf::kinect_metres_to_raw(0.0), esf::kKinectRawNoReading);
    EXPECT_EQ(esf::kinect_metres_to_raw(-1.0), esf::kKinectRawNoReading);
    EXPECT_EQ(esf::kinect_metres_to_raw(0.2), esf::kKinectRawNoReading);     // nearer than raw 0
    EXPECT_EQ(esf::kinect_metres_to_raw(1000.0), esf::kKinectRawNoReading);  // rounds to 0 steps
    EXPECT_EQ(esf::kinect_metres_to_raw(0.2904), 0);  // 1084.7 steps -> 1085 -> raw 0
}

TEST(KinectRaw, RawToMetresToRawIsIdentity) {
    for (int raw = 0; raw < 1085; ++raw) {
        const double z = esf::kinect_raw_to_metres(static_cast<std::uint16_t>(raw));
        ASSERT_TRUE(std::isfinite(z)) << raw;
        EXPECT_EQ(esf::kinect_metres_to_raw(z), raw) << z;
    }
}

TEST(KinectRaw, OneStepIsTheDisparityStepAtEveryDepth) {
    // Depth grows as raw grows; at 1 m one step is about 3 mm (the Kinect's resolution there).
    const double z1 = esf::kinect_raw_to_metres(770), z2 = esf::kinect_raw_to_metres(771);
    EXPECT_GT(z2, z1);
    EXPECT_NEAR(z2 - z1, 0.0032, 0.0001);
}

TEST(KinectRaw, FrameToCloudBackProjectsThroughTheIntrinsics) {
    esf::CameraIntrinsics camera;
    camera.width = 3;
    camera.height = 2;
    camera.cx = 1.0;
    camera.cy = 0.5;
    camera.fx = camera.fy = 525.0;
    const std::vector<std::uint16_t> raw = {770, 2047, 455, 770, 770, 1200};
    const std::vector<std::uint8_t> rgb = {1, 2, 3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 255, 0, 0};
    const esf::PointCloud cloud = esf::kinect_raw_to_cloud(raw, rgb, camera);
    ASSERT_EQ(cloud.width, 3u);
    ASSERT_EQ(cloud.height, 2u);
    // Pixel (0, 0) at 1 m: x = (0 - 1) / 525, y = (0 - 0.5) / 525.
    EXPECT_FLOAT_EQ(cloud.points[0].z(), 1.0f);
    EXPECT_FLOAT_EQ(cloud.points[0].x(), -1.0f / 525.0f);
    EXPECT_FLOAT_EQ(cloud.points[0].y(), -0.5f / 525.0f);
    EXPECT_TRUE(std::isnan(cloud.points[1].z()));  // 2047
    EXPECT_FLOAT_EQ(cloud.points[2].z(), 0.5f);
    EXPECT_FLOAT_EQ(cloud.points[2].x(), 0.5f / 525.0f);
    EXPECT_TRUE(std::isnan(cloud.points[5].x()));  // beyond zero disparity
    ASSERT_EQ(cloud.rgb.size(), 6u);
    EXPECT_EQ(cloud.rgb[0], 0x010203u);
    EXPECT_EQ(cloud.rgb[5], 0xff0000u);

    // Back to raw: the same values, no reading for both kinds of NaN.
    EXPECT_EQ(esf::kinect_cloud_to_raw(cloud, camera),
              (std::vector<std::uint16_t>{770, 2047, 455, 770, 770, 2047}));
    EXPECT_EQ(esf::kinect_cloud_to_rgb(cloud), rgb);
}

TEST(KinectRaw, WrongSizesAreRefusedByName) {
    const std::vector<std::uint16_t> raw(10, 770);
    EXPECT_CONTAINS(esf::test::error_of([&] { esf::kinect_raw_to_cloud(raw); }),
                    "has 10 depth values, expected 307200");
    const std::vector<std::uint16_t> frame(esf::kKinectFramePixels, 770);
    const std::vector<std::uint8_t> rgb(5);
    EXPECT_CONTAINS(esf::test::error_of([&] { esf::kinect_raw_to_cloud(frame, rgb); }),
                    "has 5 colour bytes");
    esf::PointCloud unorganised;
    unorganised.points.resize(4);
    unorganised.width = 4;
    EXPECT_CONTAINS(esf::test::error_of([&] { esf::kinect_cloud_to_raw(unorganised); }),
                    "needs an organised cloud of 640x480 points, got 4x1");
    EXPECT_CONTAINS(esf::test::error_of([&] { esf::kinect_raw_to_metres(1, -1.0); }),
                    "focal length");
}

}  // namespace
