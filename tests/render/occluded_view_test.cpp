// Occluded copies of a view: which points an edge hides, and the edges drawn from a seed.

#include "esf/render/occluded_view.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <stdexcept>

namespace esf {
namespace {

// A grid of points on a plane 1 m in front of the camera, slightly tilted so depths differ.
Points grid(int n) {
    Points out;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const float x = -0.2f + 0.4f * static_cast<float>(i) / static_cast<float>(n - 1);
            const float y = -0.15f + 0.3f * static_cast<float>(j) / static_cast<float>(n - 1);
            out.emplace_back(x, y, 1.0f + 0.3f * x);
        }
    return out;
}

double position(const Eigen::Vector3f& p, double angle) {
    return (p.x() * std::cos(angle) + p.y() * std::sin(angle)) / p.z();
}

TEST(OccludedView, HidesTheShareOnOneSideOfTheEdgeAndKeepsTheOrder) {
    const Points points = grid(30);  // 900 points
    for (const double angle : {0.0, 0.7, 2.0, 3.5, 5.9}) {
        const Points kept = occlude_view(points, angle, 0.35);
        ASSERT_EQ(kept.size(), points.size() - 315u);  // floor(0.35 x 900)
        // Every hidden point lies before every kept one along the direction.
        double kept_min = std::numeric_limits<double>::infinity();
        for (const auto& p : kept) kept_min = std::min(kept_min, position(p, angle));
        std::size_t k = 0;
        for (const auto& p : points) {
            if (k < kept.size() && p == kept[k]) {
                ++k;  // kept, in the input's order
                continue;
            }
            EXPECT_LE(position(p, angle), kept_min);
        }
        EXPECT_EQ(k, kept.size());
    }
}

TEST(OccludedView, TheEdgeIsStraightInTheImageWhateverTheDepth) {
    // Two points on one line of sight, at 0.5 and 2 m, lie at one image position: an edge that
    // reaches them hides both, one that stops short neither.
    Points points = grid(10);
    points.emplace_back(0.05f, 0.0f, 0.5f);
    points.emplace_back(0.2f, 0.0f, 2.0f);
    ASSERT_DOUBLE_EQ(position(points[100], 0.0), position(points[101], 0.0));
    std::size_t before = 0;  // points nearer the hidden side than the two
    for (const auto& p : points) before += position(p, 0.0) < position(points[100], 0.0);
    const auto n = static_cast<double>(points.size());
    const auto has = [](const Points& kept, const Eigen::Vector3f& p) {
        return std::find(kept.begin(), kept.end(), p) != kept.end();
    };
    const Points short_of = occlude_view(points, 0.0, (static_cast<double>(before) + 0.5) / n);
    EXPECT_TRUE(has(short_of, points[100]));
    EXPECT_TRUE(has(short_of, points[101]));
    const Points past = occlude_view(points, 0.0, (static_cast<double>(before) + 2.5) / n);
    EXPECT_FALSE(has(past, points[100]));
    EXPECT_FALSE(has(past, points[101]));
}

TEST(OccludedView, NothingOrEverythingAtTheEnds) {
    const Points points = grid(8);
    EXPECT_EQ(occlude_view(points, 1.0, 0.0), points);
    EXPECT_TRUE(occlude_view(points, 1.0, 1.0).empty());
    EXPECT_TRUE(occlude_view(Points{}, 1.0, 0.5).empty());
}

TEST(OccludedView, RefusesBadInput) {
    const Points points = grid(4);
    EXPECT_THROW(occlude_view(points, 0.0, -0.1), std::invalid_argument);
    EXPECT_THROW(occlude_view(points, 0.0, 1.5), std::invalid_argument);
    EXPECT_THROW(occlude_view(points, 0.0, std::nan("")), std::invalid_argument);
    EXPECT_THROW(occlude_view(points, std::numeric_limits<double>::infinity(), 0.5),
                 std::invalid_argument);
    Points behind = points;
    behind.emplace_back(0.0f, 0.0f, -1.0f);
    EXPECT_THROW(occlude_view(behind, 0.0, 0.5), std::invalid_argument);
    Points nan = points;
    nan.emplace_back(std::nanf(""), 0.0f, 1.0f);
    EXPECT_THROW(occlude_view(nan, 0.0, 0.5), std::invalid_argument);
}

TEST(OcclusionEdge, DrawnFromTheSeedAndTheCopyAlone) {
    std::set<std::pair<double, double>> seen;
    for (std::uint64_t seed = 0; seed < 50; ++seed)
        for (std::uint32_t copy = 0; copy < 4; ++copy) {
            const OcclusionEdge e = occlusion_edge(seed, copy);
            const OcclusionEdge again = occlusion_edge(seed, copy);
            EXPECT_EQ(e.angle, again.angle);
            EXPECT_EQ(e.fraction, again.fraction);
            EXPECT_GE(e.angle, 0.0);
            EXPECT_LT(e.angle, 2.0 * std::numbers::pi);
            EXPECT_GE(e.fraction, kMinOccludedFraction);
            EXPECT_LE(e.fraction, kMaxOccludedFraction);
            seen.emplace(e.angle, e.fraction);
        }
    EXPECT_EQ(seen.size(), 200u);  // no two seeds or copies share an edge
    // The angles cover the circle and the fractions their range.
    double below_pi = 0.0, low_fraction = 0.0;
    for (const auto& [angle, fraction] : seen) {
        below_pi += angle < std::numbers::pi;
        low_fraction += fraction < 0.5 * (kMinOccludedFraction + kMaxOccludedFraction);
    }
    EXPECT_NEAR(below_pi / 200.0, 0.5, 0.12);
    EXPECT_NEAR(low_fraction / 200.0, 0.5, 0.12);
}

}  // namespace
}  // namespace esf
