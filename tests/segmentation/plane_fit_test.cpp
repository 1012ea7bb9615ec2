// The table plane: RANSAC finds a tilted plane among outliers, the refit lands on it, and the
// result does not depend on the thread count.

#include "segmentation/plane_fit.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace {

TEST(PlaneFit, RansacAndRefitFindATiltedPlaneAmongOutliers) {
    const Eigen::Vector3f normal = Eigen::Vector3f(0.1f, -0.2f, 1.0f).normalized();
    const float d = -0.7f;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::normal_distribution<float> noise(0.0f, 0.002f);
    std::vector<Eigen::Vector3f> points;
    for (int i = 0; i < 3000; ++i) {  // 60 % on the plane, 40 % anywhere
        Eigen::Vector3f p(u(rng), u(rng), u(rng));
        if (i % 5 < 3) p -= (normal.dot(p) + d - noise(rng)) * normal;
        points.push_back(p);
    }
    esf::SegmentationOptions options;
    options.plane_distance = 0.01f;
    for (const int threads : {1, 2}) {
        options.threads = threads;
        const esf::detail::PlaneHypothesis h = esf::detail::ransac_plane(points, options);
        EXPECT_GE(h.inliers, 1800u);
        const float sign = h.normal.dot(normal) < 0.0f ? -1.0f : 1.0f;
        EXPECT_GT(sign * h.normal.dot(normal), 0.999f);
        esf::Plane plane{h.normal, h.d};
        const esf::Plane refit = esf::detail::refit_plane(points, plane, options.plane_distance);
        EXPECT_GT(sign * refit.normal.dot(normal), 0.99999f);
        EXPECT_NEAR(sign * refit.d, d, 1e-3f);
        if (threads == 2) {
            options.threads = 1;
            const esf::detail::PlaneHypothesis one = esf::detail::ransac_plane(points, options);
            EXPECT_EQ(one.normal, h.normal);
            EXPECT_EQ(one.inliers, h.inliers);
        }
    }
}

TEST(PlaneFit, DegenerateSamplesGiveNoPlane) {
    esf::SegmentationOptions options;
    const std::vector<Eigen::Vector3f> line = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
    EXPECT_EQ(esf::detail::ransac_plane(line, options).inliers, 0u);
    const std::vector<Eigen::Vector3f> two = {{0, 0, 0}, {1, 0, 0}};
    EXPECT_EQ(esf::detail::ransac_plane(two, options).inliers, 0u);
}

}  // namespace
