// ADD-S, the rotation error and the symmetry test (esf/evaluation/pose_accuracy.hpp), against
// hand-computed geometry and the generated shapes.

#include "esf/evaluation/pose_accuracy.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "esf/mesh/mesh.hpp"
#include "esf/shapes/shape_generator.hpp"
#include "support/test_meshes.hpp"

namespace {

constexpr double kPi = std::numbers::pi;

// scale x the rotation of `angle` radians about `axis`, then `t`.
Eigen::Matrix4d pose(double scale, double angle, const Eigen::Vector3d& axis,
                     const Eigen::Vector3d& t = Eigen::Vector3d::Zero()) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() =
        scale * Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
    m.topRightCorner<3, 1>() = t;
    return m;
}

TEST(PoseAccuracy, AddSOfHandComputedPoses) {
    const esf::Points two = {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0)};
    Eigen::Matrix4d shifted = Eigen::Matrix4d::Identity();
    shifted(2, 3) = 0.1;
    EXPECT_NEAR(esf::add_s(two, Eigen::Matrix4d::Identity(), shifted), 0.1, 1e-12);
    shifted(2, 3) = 0.0;
    shifted(0, 3) = 1.0;  // (0,0,0) -> nearest (1,0,0): 1; (1,0,0) -> itself: 0
    EXPECT_NEAR(esf::add_s(two, Eigen::Matrix4d::Identity(), shifted), 0.5, 1e-12);
    // A half turn about the segment's middle maps the pair onto itself: ADD-S 0.
    Eigen::Matrix4d turned = Eigen::Matrix4d::Identity();
    turned.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    turned(0, 3) = 1.0;
    EXPECT_NEAR(esf::add_s(two, Eigen::Matrix4d::Identity(), turned), 0.0, 1e-12);
    Eigen::Matrix4d scaled = Eigen::Matrix4d::Identity() * 3.0;
    scaled(3, 3) = 1.0;
    EXPECT_NEAR(esf::posed_diameter(two, scaled), 3.0, 1e-12);
    EXPECT_THROW(esf::add_s({}, Eigen::Matrix4d::Identity(), Eigen::Matrix4d::Identity()),
                 std::invalid_argument);
}

TEST(PoseAccuracy, RotationErrorIsTheAngleBetweenTheRotationsWhateverTheScales) {
    const Eigen::Vector3d axis(1.0, -2.0, 0.5);
    // 10 and 40 degrees about one axis, at scales 2 and 1.5 and other translations: 30 degrees.
    EXPECT_NEAR(esf::rotation_error_degrees(pose(2.0, kPi / 18, axis, {1, 2, 3}),
                                            pose(1.5, 4 * kPi / 18, axis, {0, 0, 1})),
                30.0, 1e-9);
    // Symmetric in its arguments, 0 for equal rotations, 180 for a half turn.
    EXPECT_NEAR(
        esf::rotation_error_degrees(pose(1.5, 4 * kPi / 18, axis), pose(2.0, kPi / 18, axis)), 30.0,
        1e-9);
    EXPECT_NEAR(esf::rotation_error_degrees(pose(1.0, 0.3, axis), pose(7.0, 0.3, axis)), 0.0, 1e-5);
    EXPECT_NEAR(esf::rotation_error_degrees(Eigen::Matrix4d::Identity(),
                                            pose(1.0, kPi, Eigen::Vector3d::UnitX())),
                180.0, 1e-6);
    // Turns about two perpendicular axes compose: 90 about z after 90 about x is 120 degrees.
    Eigen::Matrix4d both =
        pose(1.0, kPi / 2, Eigen::Vector3d::UnitZ()) * pose(1.0, kPi / 2, Eigen::Vector3d::UnitX());
    EXPECT_NEAR(esf::rotation_error_degrees(Eigen::Matrix4d::Identity(), both), 120.0, 1e-9);
    // A mirror, a flattened block and a pose that is not finite are refused.
    Eigen::Matrix4d mirror = Eigen::Matrix4d::Identity();
    mirror(0, 0) = -1.0;
    EXPECT_THROW(esf::rotation_error_degrees(Eigen::Matrix4d::Identity(), mirror),
                 std::invalid_argument);
    Eigen::Matrix4d flat = Eigen::Matrix4d::Identity();
    flat(2, 2) = 0.0;
    EXPECT_THROW(esf::rotation_error_degrees(flat, Eigen::Matrix4d::Identity()),
                 std::invalid_argument);
    Eigen::Matrix4d nan = Eigen::Matrix4d::Identity();
    nan(1, 3) = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(esf::rotation_error_degrees(Eigen::Matrix4d::Identity(), nan),
                 std::invalid_argument);
}

TEST(PoseAccuracy, SymmetryOfHandMadeAndGeneratedShapes) {
    // A box of three different sides: half turns about its axes. With a knob on one end of a
    // side: none.
    EXPECT_TRUE(esf::has_symmetry(esf::test::standing_box(0.1, 0.06, 0.04)));
    EXPECT_FALSE(esf::has_symmetry(esf::test::knobbed_box(0.1, 0.06, 0.04, 0.024)));
    // Turned shapes (any turn about their axis) have one; a mug's handle breaks it.
    for (const std::string category : {"bottle", "bowl", "donut", "toilet_paper"})
        EXPECT_TRUE(esf::has_symmetry(esf::generate_shape(category, 1, 0))) << category;
    EXPECT_FALSE(esf::has_symmetry(esf::generate_shape("mug", 1, 0)));
    // The answer is the mesh's, whatever frame it is given in.
    esf::Mesh moved = esf::generate_shape("mug", 1, 0);
    const Eigen::Matrix3f turn =
        Eigen::AngleAxisf(0.7f, Eigen::Vector3f(1, 2, 3).normalized()).toRotationMatrix();
    for (Eigen::Vector3f& v : moved.vertices) v = turn * v + Eigen::Vector3f(1, 0, 0);
    EXPECT_FALSE(esf::has_symmetry(moved));
    EXPECT_THROW(esf::has_symmetry(esf::Mesh{}), std::invalid_argument);
}

}  // namespace
