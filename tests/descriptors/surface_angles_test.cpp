#include "esf/descriptors/surface_angles.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "support/error_of.hpp"
#include "support/facing_square.hpp"

namespace esf {
namespace {

using test::error_of;

using test::facing_square;

/// The front half of a cylinder (radius 5 cm, height 12 cm, axis along y) 0.8 m in front of
/// the sensor, on a regular grid of 1 degree by 2 mm.
Points half_cylinder() {
    Points points;
    for (int a = 0; a <= 180; ++a)
        for (int h = -30; h <= 30; ++h) {
            const double angle = a * std::acos(-1.0) / 180.0;
            points.emplace_back(static_cast<float>(0.05 * std::cos(angle)),
                                static_cast<float>(0.002 * h),
                                static_cast<float>(0.8 - 0.05 * std::sin(angle)));
        }
    return points;
}

float block_sum(const SurfaceAngleHistograms& h, int first, int count) {
    return std::accumulate(h.begin() + first, h.begin() + first + count, 0.0f);
}

constexpr int kBeta = 4 * kSurfaceAngleBins;
constexpr int kSigma = kBeta + kSurfaceViewpointBins;

TEST(SurfaceAngles, EveryHistogramSumsToOne) {
    const SurfaceAngleHistograms h = compute_surface_angles(half_cylinder());
    for (int b = 0; b < 4; ++b)
        EXPECT_NEAR(block_sum(h, b * kSurfaceAngleBins, kSurfaceAngleBins), 1.0f, 1e-5f) << b;
    EXPECT_NEAR(block_sum(h, kBeta, kSurfaceViewpointBins), 1.0f, 1e-5f);
    EXPECT_NEAR(block_sum(h, kSigma, kSurfaceVariationBins), 1.0f, 1e-5f);
    for (const float v : h) EXPECT_GE(v, 0.0f);
}

TEST(SurfaceAngles, PlaneFacingTheSensor) {
    // Every normal is (0, 0, -1), turned towards the sensor, and the view direction from the
    // centre (0, 0, 1) is (0, 0, -1): beta = 1, the last bin. The plane is flat: sigma = 0, the
    // first bin. The normals equal the mean normal u, so alpha = 0 (w_1 is orthogonal to u),
    // phi = 0 (d lies in the plane) and theta = atan2(0, 1) = 0: the middle bins.
    const SurfaceAngleHistograms h = compute_surface_angles(facing_square(0.2f, 1.0f));
    EXPECT_FLOAT_EQ(h[kBeta + kSurfaceViewpointBins - 1], 1.0f);
    EXPECT_FLOAT_EQ(h[kSigma], 1.0f);
    const int middle = kSurfaceAngleBins / 2;  // 15 bins over [-1, 1] or [-pi, pi]: 0 in bin 7
    EXPECT_FLOAT_EQ(h[0 * kSurfaceAngleBins + middle], 1.0f);
    EXPECT_FLOAT_EQ(h[1 * kSurfaceAngleBins + middle], 1.0f);
    EXPECT_FLOAT_EQ(h[2 * kSurfaceAngleBins + middle], 1.0f);
}

TEST(SurfaceAngles, CurvedSurfaceSpreadsTheViewpointAngles) {
    const SurfaceAngleHistograms plane = compute_surface_angles(facing_square(0.1f, 0.8f));
    const SurfaceAngleHistograms cylinder = compute_surface_angles(half_cylinder());
    auto occupied = [](const SurfaceAngleHistograms& h) {
        int n = 0;
        for (int i = kBeta; i < kBeta + kSurfaceViewpointBins; ++i) n += h[i] > 0.0f;
        return n;
    };
    // The cylinder's normals turn through 180 degrees: beta = n . v covers [0, 1], the upper
    // half of the bins.
    EXPECT_EQ(occupied(plane), 1);
    EXPECT_GE(occupied(cylinder), 6);
}

TEST(SurfaceAngles, DoesNotDependOnPointOrder) {
    Points points = half_cylinder();
    const SurfaceAngleHistograms forward = compute_surface_angles(points);
    std::reverse(points.begin(), points.end());
    const SurfaceAngleHistograms backward = compute_surface_angles(points);
    for (std::size_t i = 0; i < forward.size(); ++i) EXPECT_NEAR(forward[i], backward[i], 1e-6f);
}

TEST(SurfaceAngles, NonFinitePointsAreDropped) {
    Points points = half_cylinder();
    const SurfaceAngleHistograms clean = compute_surface_angles(points);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    points.emplace_back(nan, 0.0f, 1.0f);
    points.emplace_back(std::numeric_limits<float>::infinity(), 0.0f, 1.0f);
    EXPECT_EQ(compute_surface_angles(points), clean);
}

TEST(SurfaceAngles, Errors) {
    EXPECT_EQ(error_of([] {
                  compute_surface_angles(Points{{0, 0, 1}, {0, 0.1f, 1}});
              }),
              "surface angles: needs at least 3 finite points, got 2");
    Points line;
    for (int i = 0; i < 100; ++i) line.emplace_back(0.001f * static_cast<float>(i), 0.0f, 1.0f);
    EXPECT_EQ(error_of([&] { compute_surface_angles(line); }),
              "surface angles: no surface normal in a cloud of 100 points (too sparse or on a "
              "line)");
    SurfaceAngleOptions options;
    options.cell_size = 0.0;
    EXPECT_EQ(error_of([&] { compute_surface_angles(half_cylinder(), options); }),
              "surface angles: cell size must be positive and finite, got 0.000000");
}

}  // namespace
}  // namespace esf
