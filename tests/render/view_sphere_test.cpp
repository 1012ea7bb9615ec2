#include "esf/render/view_sphere.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/error_of.hpp"

namespace {

constexpr double kPhi = 1.6180339887498949;

using esf::test::error_of;

TEST(ViewSphere, CountsPerLevel) {
    EXPECT_EQ(esf::view_count(0), 20u);
    EXPECT_EQ(esf::view_count(1), 80u);
    EXPECT_EQ(esf::view_count(2), 320u);
    EXPECT_EQ(esf::view_count(6), 81920u);
    for (int level = 0; level <= 3; ++level)
        EXPECT_EQ(esf::view_sphere(level).size(), esf::view_count(level)) << "level " << level;
}

TEST(ViewSphere, LevelZeroIsTheDodecahedron) {
    // The face centres of an icosahedron are the vertices of a dodecahedron:
    // (+-1, +-1, +-1), (0, +-phi, +-1/phi) and its cyclic permutations, all of norm sqrt(3).
    std::vector<Eigen::Vector3d> expected;
    for (double a : {-1.0, 1.0}) {
        for (double b : {-1.0, 1.0}) {
            for (double c : {-1.0, 1.0}) expected.emplace_back(a, b, c);
            expected.emplace_back(0.0, a * kPhi, b / kPhi);
            expected.emplace_back(b / kPhi, 0.0, a * kPhi);
            expected.emplace_back(a * kPhi, b / kPhi, 0.0);
        }
    }
    ASSERT_EQ(expected.size(), 20u);
    const std::vector<Eigen::Vector3d> views = esf::view_sphere(0);
    for (const Eigen::Vector3d& e : expected) {
        const Eigen::Vector3d unit = e / std::sqrt(3.0);
        int matches = 0;
        for (const Eigen::Vector3d& v : views) matches += (v - unit).norm() < 1e-12 ? 1 : 0;
        EXPECT_EQ(matches, 1) << e.transpose();
    }
}

TEST(ViewSphere, UnitDistinctBalancedAndEvenlySpread) {
    for (int level = 0; level <= 2; ++level) {
        const std::vector<Eigen::Vector3d> views = esf::view_sphere(level);
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        double min_angle = std::numbers::pi;
        double max_nearest = 0.0;
        for (std::size_t i = 0; i < views.size(); ++i) {
            EXPECT_NEAR(views[i].norm(), 1.0, 1e-12);
            sum += views[i];
            double nearest = std::numbers::pi;
            for (std::size_t j = 0; j < views.size(); ++j) {
                if (i == j) continue;
                const double angle = std::acos(std::clamp(views[i].dot(views[j]), -1.0, 1.0));
                nearest = std::min(nearest, angle);
            }
            min_angle = std::min(min_angle, nearest);
            max_nearest = std::max(max_nearest, nearest);
        }
        // Icosahedral symmetry: the directions cancel out.
        EXPECT_LT(sum.norm(), 1e-9) << "level " << level;
        // Area per view 4 pi / n; neighbours are about sqrt of that apart, never much closer
        // or farther (geodesic subdivision keeps the cells within a factor ~1.3).
        const double spacing =
            std::sqrt(4.0 * std::numbers::pi / static_cast<double>(views.size()));
        EXPECT_GT(min_angle, 0.75 * spacing) << "level " << level;
        EXPECT_LT(max_nearest, 1.25 * spacing) << "level " << level;
    }
}

TEST(ViewSphere, ChildrenFollowTheirParentFace) {
    // View i of level 1 lies in icosahedron face i / 4: its nearest level-0 view is that face's.
    const std::vector<Eigen::Vector3d> parents = esf::view_sphere(0);
    const std::vector<Eigen::Vector3d> children = esf::view_sphere(1);
    for (std::size_t i = 0; i < children.size(); ++i) {
        std::size_t best = 0;
        for (std::size_t p = 1; p < parents.size(); ++p) {
            if (children[i].dot(parents[p]) > children[i].dot(parents[best])) best = p;
        }
        EXPECT_EQ(best, i / 4) << "view " << i;
    }
    // The fourth child is the middle triangle, whose centre is the parent's centre.
    for (std::size_t p = 0; p < parents.size(); ++p)
        EXPECT_LT((children[4 * p + 3] - parents[p]).norm(), 1e-12);
}

TEST(ViewSphere, RejectsBadLevels) {
    EXPECT_THROW(esf::view_sphere(-1), std::invalid_argument);
    EXPECT_EQ(error_of([] { esf::view_sphere(7); }), "view sphere level must be in [0, 6], got 7");
    EXPECT_EQ(error_of([] { esf::view_count(-1); }), "view sphere level must be in [0, 6], got -1");
}

TEST(LookAt, HorizontalCameraHasWorldZUp) {
    // Camera at +x looking at the origin: forward -x, image up = world +z, image right = +y
    // (facing -x with z up, +y is on the right).
    const Eigen::Isometry3d pose = esf::look_at({1, 0, 0}, {0, 0, 0});
    EXPECT_LT((pose * Eigen::Vector3d(0, 0, 0) - Eigen::Vector3d(0, 0, 1)).norm(), 1e-15);
    EXPECT_LT((pose * Eigen::Vector3d(0, 0, 1) - Eigen::Vector3d(0, -1, 1)).norm(), 1e-15);
    EXPECT_LT((pose * Eigen::Vector3d(0, 1, 0) - Eigen::Vector3d(1, 0, 1)).norm(), 1e-15);
    EXPECT_LT((pose * Eigen::Vector3d(1, 0, 0)).norm(), 1e-15);  // the eye
}

TEST(LookAt, VerticalCameraFallsBackToWorldY) {
    // Looking straight down from +z: image up = world +y, image right = world +x.
    const Eigen::Isometry3d pose = esf::look_at({0, 0, 2}, {0, 0, 0});
    EXPECT_LT((pose * Eigen::Vector3d(0, 0, 0) - Eigen::Vector3d(0, 0, 2)).norm(), 1e-15);
    EXPECT_LT((pose * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(1, 0, 2)).norm(), 1e-15);
    EXPECT_LT((pose * Eigen::Vector3d(0, 1, 0) - Eigen::Vector3d(0, -1, 2)).norm(), 1e-15);
}

TEST(LookAt, EveryViewIsARotationLookingAtTheCentre) {
    const Eigen::Vector3d centre(0.1, -0.2, 0.3);
    for (const Eigen::Vector3d& direction : esf::view_sphere(2)) {
        const Eigen::Isometry3d pose = esf::look_at(centre + 0.7 * direction, centre);
        const Eigen::Matrix3d r = pose.linear();
        EXPECT_LT((r * r.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
        EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
        EXPECT_LT((pose * centre - Eigen::Vector3d(0, 0, 0.7)).norm(), 1e-12);
        // Image up (camera -y) never points down in the world.
        const Eigen::Vector3d image_up = -r.row(1).transpose();
        if (std::abs(direction.z()) <= 0.99) {
            EXPECT_GE(image_up.z(), 0.0);
        }
    }
}

TEST(LookAt, RejectsDegenerateInput) {
    EXPECT_EQ(error_of([] {
                  esf::look_at({1, 2, 3}, {1, 2, 3});
              }),
              "look_at: eye and target are the same point");
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(error_of([&] {
                  esf::look_at({nan, 0, 0}, {0, 0, 0});
              }),
              "look_at: eye and target must be finite");
}

}  // namespace
