#include "segmentation/container_parts.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace {

using Eigen::Vector3f;

// Points of a vertical wall on the circle (cx, cy, r), angles a0..a1, heights 0..h (z up; the
// table is z = 0).
void add_wall(std::vector<Vector3f>& points, std::vector<std::uint32_t>& group, std::uint32_t id,
              float cx, float cy, float r, float a0, float a1, float h) {
    for (int i = 0; i <= 60; ++i) {
        const float a = a0 + (a1 - a0) * static_cast<float>(i) / 60.0f;
        for (int k = 1; k <= 10; ++k) {
            points.emplace_back(cx + r * std::cos(a), cy + r * std::sin(a),
                                h * static_cast<float>(k) / 10.0f);
            group.push_back(id);
        }
    }
}

constexpr float kPi = std::numbers::pi_v<float>;
const Vector3f kUp = Vector3f::UnitZ();

TEST(ContainerParts, InsideJoinsOutsideOfOneCup) {
    std::vector<Vector3f> points;
    std::vector<std::uint32_t> group;
    add_wall(points, group, 0, 0, 0, 0.040f, -kPi, 0, 0.10f);           // front outside
    add_wall(points, group, 1, 0, 0, 0.037f, 0.1f, kPi - 0.1f, 0.10f);  // back inside
    esf::detail::join_container_parts(points, group, kUp, 0.0f);
    for (const std::uint32_t g : group) EXPECT_EQ(g, 0u);
}

TEST(ContainerParts, TwoCansSideBySideStayApart) {
    std::vector<Vector3f> points;
    std::vector<std::uint32_t> group;
    add_wall(points, group, 0, 0, 0, 0.035f, -kPi, 0, 0.12f);
    add_wall(points, group, 1, 0.071f, 0, 0.035f, -kPi, 0, 0.12f);  // touching the first
    esf::detail::join_container_parts(points, group, kUp, 0.0f);
    EXPECT_EQ(group.front(), 0u);
    EXPECT_EQ(group.back(), 1u);
}

TEST(ContainerParts, ObjectStandingOnACanStaysApart) {
    std::vector<Vector3f> points;
    std::vector<std::uint32_t> group;
    add_wall(points, group, 0, 0, 0, 0.040f, -kPi, 0, 0.10f);
    // A smaller can on top: within the footprint, but above the first one's top.
    const std::size_t first = points.size();
    add_wall(points, group, 1, 0, 0, 0.030f, -kPi, 0, 0.08f);
    for (std::size_t k = first; k < points.size(); ++k) points[k].z() += 0.10f;
    esf::detail::join_container_parts(points, group, kUp, 0.0f);
    EXPECT_EQ(group.back(), 1u);
    // The same inside the first one's walls and below its top: joined.
    for (std::size_t k = first; k < points.size(); ++k) points[k].z() -= 0.10f;
    for (std::size_t k = first; k < points.size(); ++k) group[k] = 1;
    esf::detail::join_container_parts(points, group, kUp, 0.0f);
    EXPECT_EQ(group.back(), 0u);
}

}  // namespace
