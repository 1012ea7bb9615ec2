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

namespace {

// A 60 x 60 organised frame of a container on a table (z = 0). The pixel at distance d (pixels)
// from the image centre shows: for d in [18, 24), the container's rim (on its 5 cm circle, 5 cm
// high; the cluster, where `keep(row, col)`); for d < 18, its floor (within 4 cm of the centre,
// 3 mm high); further out, the table.
struct FloorFrame {
    static constexpr std::uint32_t kSize = 60;
    std::vector<Vector3f> points;
    esf::Cluster cluster;
    std::size_t floor_pixels = 0;

    template <class Keep>
    explicit FloorFrame(Keep keep) {
        for (std::uint32_t row = 0; row < kSize; ++row)
            for (std::uint32_t col = 0; col < kSize; ++col) {
                const float dx = static_cast<float>(col) - 29.5f;
                const float dy = static_cast<float>(row) - 29.5f;
                const float d = std::hypot(dx, dy), a = std::atan2(dy, dx);
                const std::uint32_t i = row * kSize + col;
                if (d >= 18.0f && d < 24.0f && keep(row, col)) {
                    points.emplace_back(0.05f * std::cos(a), 0.05f * std::sin(a), 0.05f);
                    cluster.indices.push_back(i);
                    cluster.points.push_back(points.back());
                } else if (d < 18.0f) {
                    points.emplace_back(0.04f * d / 18.0f * std::cos(a),
                                        0.04f * d / 18.0f * std::sin(a), 0.003f);
                    ++floor_pixels;
                } else {
                    points.emplace_back(0.002f * d * std::cos(a), 0.002f * d * std::sin(a), 0.0f);
                }
            }
    }
};

esf::Plane table_plane() {
    esf::Plane plane;
    plane.normal = Vector3f::UnitZ();
    plane.d = 0.0f;
    return plane;
}

TEST(ContainerFloors, TheFloorInsideARoundRimJoinsIt) {
    FloorFrame frame([](std::uint32_t, std::uint32_t) { return true; });
    std::vector<esf::Cluster> clusters = {frame.cluster};
    const std::size_t rim = clusters[0].indices.size();
    const std::size_t taken = esf::detail::join_container_floors(frame.points, FloorFrame::kSize,
                                                                 table_plane(), 0.0075f, clusters);
    // Every floor pixel within the circle less 1 cm (4 cm of the rim's 5 cm) is walled in.
    EXPECT_EQ(taken, frame.floor_pixels);
    const esf::Cluster& c = clusters[0];
    ASSERT_EQ(c.indices.size(), rim + taken);
    ASSERT_EQ(c.points.size(), c.indices.size());
    EXPECT_TRUE(std::is_sorted(c.indices.begin(), c.indices.end()));
    for (std::size_t k = 0; k < c.indices.size(); ++k)
        EXPECT_EQ(c.points[k], frame.points[c.indices[k]]);
    // Table pixels (z = 0, outside the rim) stay out.
    for (const Vector3f& p : c.points) EXPECT_GT(p.z(), 0.0f);
}

TEST(ContainerFloors, NotWhereTheObjectDoesNotWallItIn) {
    // The rim's upper half only (an overhang seen from the side): round, but nothing of the
    // object below the low pixels.
    FloorFrame half([](std::uint32_t row, std::uint32_t) { return row < 30; });
    std::vector<esf::Cluster> clusters = {half.cluster};
    EXPECT_EQ(esf::detail::join_container_floors(half.points, FloorFrame::kSize, table_plane(),
                                                 0.0075f, clusters),
              0u);
    // Above min_height the floor is no business of this rule (it is an object point already).
    FloorFrame full([](std::uint32_t, std::uint32_t) { return true; });
    clusters = {full.cluster};
    EXPECT_EQ(esf::detail::join_container_floors(full.points, FloorFrame::kSize, table_plane(),
                                                 0.002f, clusters),
              0u);
}

}  // namespace
