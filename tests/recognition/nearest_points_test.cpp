// The grid's nearest point within a radius against brute force: random surfaces and clouds,
// queries inside and outside the grid, radii from below a cell to beyond the cloud, hints, points
// that are not finite, ties, huge extents and an empty set.

#include "recognition/nearest_points.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "core/splitmix64.hpp"

namespace {

using esf::Points;
using esf::detail::NearestPoints;

constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();

// The squared distance as the grid sums it (x, y, z in float).
float squared(const Eigen::Vector3f& q, const Eigen::Vector3f& p) {
    const float dx = q.x() - p.x(), dy = q.y() - p.y(), dz = q.z() - p.z();
    float d = dx * dx;
    d += dy * dy;
    d += dz * dz;
    return d;
}

// Brute force: the least squared distance at most radius_squared, or -1 for none.
float nearest_squared(const Points& points, const Eigen::Vector3f& q, float radius_squared) {
    float best = -1.0f;
    for (const Eigen::Vector3f& p : points) {
        if (!p.allFinite()) continue;
        const float d = squared(q, p);
        if (d <= radius_squared && (best < 0.0f || d < best)) best = d;
    }
    return best;
}

class Uniform {
  public:
    explicit Uniform(std::uint64_t seed) : random_(seed) {}
    float operator()(float lo, float hi) {
        return lo + static_cast<float>(random_.uniform()) * (hi - lo);
    }

  private:
    esf::detail::SplitMix64 random_;
};

// Checks `queries` random queries around `points` against brute force.
void expect_brute_force(const Points& points, float cell, std::uint64_t seed, float spread,
                        int queries = 400) {
    const NearestPoints grid(points, cell);
    Uniform uniform(seed);
    for (int k = 0; k < queries; ++k) {
        const Eigen::Vector3f q(uniform(-spread, spread), uniform(-spread, spread),
                                uniform(-spread, spread));
        const float radius = uniform(0.0005f, 0.2f);
        const float radius_squared = radius * radius;
        const float expected = nearest_squared(points, q, radius_squared);
        // Without a hint, and with a hint that is a random point (near or not).
        const std::size_t hint =
            points.empty() ? kNone
                           : static_cast<std::size_t>(uniform(0.0f, 1.0f) *
                                                      static_cast<float>(points.size() - 1));
        for (const std::size_t h : {kNone, hint}) {
            std::size_t index = kNone;
            float d = -1.0f;
            const bool found = grid.nearest_within(q, radius_squared, h, index, d);
            ASSERT_EQ(found, expected >= 0.0f) << "query " << k << " radius " << radius;
            if (!found) continue;
            ASSERT_LT(index, points.size());
            EXPECT_EQ(d, expected) << "query " << k;
            EXPECT_EQ(squared(q, points[index]), d) << "query " << k;
        }
    }
}

TEST(NearestPoints, MatchesBruteForceOnACloud) {
    Uniform uniform(7);
    Points points;
    for (int i = 0; i < 1000; ++i)
        points.emplace_back(uniform(-0.1f, 0.1f), uniform(-0.05f, 0.05f), uniform(0.8f, 0.9f));
    // The queries about the same box: shift them onto it.
    Points shifted = points;
    for (Eigen::Vector3f& p : shifted) p.z() -= 0.85f;
    for (const float cell : {0.002f, 0.01f, 0.03f, 1.0f})
        expect_brute_force(shifted, cell, 11, 0.15f);
}

TEST(NearestPoints, MatchesBruteForceOnASurface) {
    // A sphere's surface: most cells empty, the rest thin.
    Uniform uniform(3);
    Points points;
    for (int i = 0; i < 2000; ++i) {
        Eigen::Vector3f p(uniform(-1.0f, 1.0f), uniform(-1.0f, 1.0f), uniform(-1.0f, 1.0f));
        if (p.norm() < 1e-3f) continue;
        points.push_back(0.08f * p.normalized());
    }
    expect_brute_force(points, 0.006f, 5, 0.12f);
}

TEST(NearestPoints, FindsAPointAtExactlyTheRadius) {
    const Points points = {Eigen::Vector3f(0.0f, 0.0f, 0.0f), Eigen::Vector3f(0.5f, 0.0f, 0.0f)};
    const NearestPoints grid(points, 0.01f);
    std::size_t index = kNone;
    float d = 0.0f;
    const Eigen::Vector3f q(0.25f, 0.0f, 0.0f);
    const float exact = squared(q, points[0]);
    ASSERT_TRUE(grid.nearest_within(q, exact, kNone, index, d));
    EXPECT_EQ(d, exact);
    EXPECT_FALSE(grid.nearest_within(q, std::nextafter(exact, 0.0f), kNone, index, d));
}

TEST(NearestPoints, AHintIsReplacedOnlyByAStrictlyNearerPoint) {
    // Two points at the same distance from the query: the hint, tried first, wins the tie.
    const Points points = {Eigen::Vector3f(-0.01f, 0.0f, 0.0f), Eigen::Vector3f(0.01f, 0.0f, 0.0f),
                           Eigen::Vector3f(0.0f, 0.3f, 0.0f)};
    const NearestPoints grid(points, 0.005f);
    std::size_t index = kNone;
    float d = 0.0f;
    for (const std::size_t hint : {std::size_t{0}, std::size_t{1}}) {
        ASSERT_TRUE(grid.nearest_within(Eigen::Vector3f::Zero(), 1.0f, hint, index, d));
        EXPECT_EQ(index, hint);
    }
    // A far hint gives way to the nearer point.
    ASSERT_TRUE(grid.nearest_within(Eigen::Vector3f(0.0f, 0.29f, 0.0f), 1.0f, 0, index, d));
    EXPECT_EQ(index, 2u);
}

TEST(NearestPoints, NeverFindsPointsThatAreNotFinite) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    const Points points = {Eigen::Vector3f(nan, 0.0f, 0.0f), Eigen::Vector3f(0.1f, 0.0f, 0.0f),
                           Eigen::Vector3f(inf, 0.0f, 0.0f), Eigen::Vector3f(0.0f, -inf, 0.0f)};
    const NearestPoints grid(points, 0.01f);
    std::size_t index = kNone;
    float d = 0.0f;
    ASSERT_TRUE(grid.nearest_within(Eigen::Vector3f::Zero(), 1.0f, 0, index, d));
    EXPECT_EQ(index, 1u);
    // A query that is not finite finds nothing.
    EXPECT_FALSE(grid.nearest_within(Eigen::Vector3f(nan, 0.0f, 0.0f), 1.0f, kNone, index, d));
    EXPECT_FALSE(grid.nearest_within(Eigen::Vector3f(inf, 0.0f, 0.0f), 1.0f, kNone, index, d));
    // Only points that are not finite: nothing, and no grid to read.
    const NearestPoints none({Eigen::Vector3f(nan, nan, nan)}, 0.01f);
    EXPECT_FALSE(none.nearest_within(Eigen::Vector3f::Zero(), 1e30f, kNone, index, d));
}

TEST(NearestPoints, StaysSmallAndRightOverHugeExtents) {
    // Points a world apart: the cells grow so that the grid stays small; answers stay exact.
    Uniform uniform(13);
    Points points;
    for (int i = 0; i < 200; ++i)
        points.emplace_back(uniform(-0.1f, 0.1f), uniform(-0.1f, 0.1f), uniform(-0.1f, 0.1f));
    points.emplace_back(3e37f, -3e37f, 3e37f);
    points.emplace_back(-3e37f, 3e37f, -3e37f);
    expect_brute_force(points, 0.001f, 17, 0.15f, 100);
    const NearestPoints grid(points, 0.001f);
    std::size_t index = kNone;
    float d = 0.0f;
    ASSERT_TRUE(grid.nearest_within(Eigen::Vector3f(3e37f, -3e37f, 3e37f), 1.0f, kNone, index, d));
    EXPECT_EQ(index, 200u);
    // A query far outside the grid, with a radius that cannot reach it.
    EXPECT_FALSE(grid.nearest_within(Eigen::Vector3f(0.0f, 1e20f, 0.0f), 1.0f, kNone, index, d));
}

TEST(NearestPoints, AnEmptySetFindsNothing) {
    const NearestPoints grid(Points{}, 0.01f);
    std::size_t index = kNone;
    float d = 0.0f;
    EXPECT_FALSE(grid.nearest_within(Eigen::Vector3f::Zero(), 1.0f, kNone, index, d));
    EXPECT_FALSE(grid.nearest_within(Eigen::Vector3f::Zero(), 1.0f, 0, index, d));
}

TEST(NearestPoints, RefusesACellThatIsNotPositive) {
    for (const float cell : {0.0f, -0.01f, std::numeric_limits<float>::quiet_NaN(),
                             std::numeric_limits<float>::infinity()})
        EXPECT_THROW(NearestPoints(Points{Eigen::Vector3f::Zero()}, cell), std::invalid_argument);
}

}  // namespace
