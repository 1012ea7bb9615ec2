#include "esf/render/sensor_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(SensorModel, ParseAndPrint) {
    EXPECT_EQ(esf::parse_enum<esf::SensorNoise>("none"), esf::SensorNoise::kNone);
    EXPECT_EQ(esf::parse_enum<esf::SensorNoise>("kinect"), esf::SensorNoise::kKinect);
    EXPECT_STREQ(esf::to_string(esf::SensorNoise::kNone), "none");
    EXPECT_STREQ(esf::to_string(esf::SensorNoise::kKinect), "kinect");
    try {
        esf::parse_enum<esf::SensorNoise>("kinect2");
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "unknown sensor noise 'kinect2' (expected none or kinect)");
    }
}

TEST(SensorModel, AxialSigmaOfNguyen2012) {
    // 0.0012 + 0.0019 (z - 0.4)^2 below 60 degrees.
    EXPECT_DOUBLE_EQ(esf::kinect_axial_sigma(0.4, 0.0), 0.0012);
    EXPECT_DOUBLE_EQ(esf::kinect_axial_sigma(1.4, 30 * kDeg), 0.0012 + 0.0019);
    EXPECT_DOUBLE_EQ(esf::kinect_axial_sigma(2.4, 60 * kDeg), 0.0012 + 0.0019 * 4);
    // At 70 degrees, theta / (90 - theta) = 3.5: + 0.0001 / sqrt(z) * 12.25.
    EXPECT_NEAR(esf::kinect_axial_sigma(1.0, 70 * kDeg), 0.0012 + 0.0019 * 0.36 + 0.001225, 1e-15);
    EXPECT_NEAR(esf::kinect_axial_sigma(0.25, 70 * kDeg), 0.0012 + 0.0019 * 0.0225 + 0.0002 * 12.25,
                1e-15);
}

TEST(SensorModel, DisparityQuantisation) {
    // fx * b = 525 * 0.075 = 39.375 pixel metres; steps of 1/8 pixel.
    EXPECT_DOUBLE_EQ(esf::quantise_kinect_depth(1.0, 525.0), 1.0);              // 315 steps exactly
    EXPECT_DOUBLE_EQ(esf::quantise_kinect_depth(1.001, 525.0), 1.0);            // 314.69 -> 315
    EXPECT_DOUBLE_EQ(esf::quantise_kinect_depth(0.5, 525.0), 0.5);              // 630
    EXPECT_DOUBLE_EQ(esf::quantise_kinect_depth(0.71, 525.0), 39.375 / 55.5);   // 443.66 -> 444
    EXPECT_DOUBLE_EQ(esf::quantise_kinect_depth(3.0, 525.0), 39.375 / 13.125);  // 105 exactly
    // Too far for a disparity step: no depth.
    EXPECT_TRUE(std::isinf(esf::quantise_kinect_depth(1e6, 525.0)));
}

TEST(SensorModel, GrazingDropProbability) {
    EXPECT_EQ(esf::grazing_drop_probability(0.0), 0.0);
    EXPECT_EQ(esf::grazing_drop_probability(65 * kDeg), 0.0);
    EXPECT_NEAR(esf::grazing_drop_probability(70 * kDeg), 0.15625, 1e-12);  // x = 1/4
    EXPECT_NEAR(esf::grazing_drop_probability(75 * kDeg), 0.5, 1e-12);
    EXPECT_NEAR(esf::grazing_drop_probability(80 * kDeg), 0.84375, 1e-12);
    EXPECT_EQ(esf::grazing_drop_probability(85 * kDeg), 1.0);
    EXPECT_EQ(esf::grazing_drop_probability(90 * kDeg), 1.0);
}

TEST(SensorModel, PixelRandomIsKeyedAndWellDistributed) {
    esf::PixelRandom a(1, 2, 3), b(1, 2, 3), c(1, 2, 4), d(2, 2, 3), e(1, 3, 3);
    const double first = a.uniform();
    EXPECT_EQ(first, b.uniform());
    EXPECT_NE(first, c.uniform());
    EXPECT_NE(first, d.uniform());
    EXPECT_NE(first, e.uniform());

    // One normal per pixel key, as the renderer draws them.
    const int n = 200000;
    double sum = 0.0, sum2 = 0.0, sum4 = 0.0;
    int within_one = 0, beyond_three = 0;
    for (int i = 0; i < n; ++i) {
        esf::PixelRandom random(9, 0, static_cast<std::uint64_t>(i));
        const double x = random.normal();
        sum += x;
        sum2 += x * x;
        sum4 += x * x * x * x;
        within_one += std::abs(x) < 1.0 ? 1 : 0;
        beyond_three += std::abs(x) > 3.0 ? 1 : 0;
    }
    // Standard errors: mean 0.0022, variance 0.0032, kurtosis ~0.02.
    EXPECT_NEAR(sum / n, 0.0, 0.01);
    EXPECT_NEAR(sum2 / n, 1.0, 0.015);
    EXPECT_NEAR(sum4 / n, 3.0, 0.1);
    EXPECT_NEAR(within_one / double(n), 0.6827, 0.005);
    EXPECT_NEAR(beyond_three / double(n), 0.0027, 0.0006);

    double usum = 0.0;
    esf::PixelRandom u(5, 6, 7);
    for (int i = 0; i < n; ++i) {
        const double x = u.uniform();
        ASSERT_GE(x, 0.0);
        ASSERT_LT(x, 1.0);
        usum += x;
    }
    EXPECT_NEAR(usum / n, 0.5, 0.003);
}

TEST(SensorModel, MeasureIsUnbiasedWithTheModelsSpread) {
    // 1.5 m, face-on: sigma = 0.0012 + 0.0019 * 1.21 = 3.5 mm, step = 1.5^2 / 315 = 7.1 mm.
    // The quantised depths are unbiased; their spread is about sqrt(sigma^2 + step^2 / 12).
    const int n = 100000;
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; ++i) {
        esf::PixelRandom random(1, 0, static_cast<std::uint64_t>(i));
        const double z = esf::kinect_measure(1.5, 1.0, 525.0, random);
        ASSERT_TRUE(std::isfinite(z));
        const double k = 8.0 * 39.375 / z;
        ASSERT_NEAR(k, std::round(k), 1e-9);
        sum += z;
        sum2 += (z - 1.5) * (z - 1.5);
    }
    const double sigma = 0.0012 + 0.0019 * 1.21;
    const double step = 1.5 * 1.5 / 315.0;
    EXPECT_NEAR(sum / n, 1.5, 1e-4);
    EXPECT_NEAR(std::sqrt(sum2 / n), std::sqrt(sigma * sigma + step * step / 12.0), 3e-4);

    // At 80 degrees the smoothstep drops 84 % of the pixels.
    int dropped = 0;
    for (int i = 0; i < n; ++i) {
        esf::PixelRandom random(2, 0, static_cast<std::uint64_t>(i));
        dropped += std::isnan(esf::kinect_measure(0.8, std::cos(80 * kDeg), 525.0, random)) ? 1 : 0;
    }
    EXPECT_NEAR(dropped / double(n), 0.84375, 0.005);
}

}  // namespace
