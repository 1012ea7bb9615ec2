// 2-D hulls against brute force: the monotone chain's vertices are exactly the points with a
// supporting line, the octagon filter changes nothing, point-in-hull agrees with the edge
// tests, and the smallest rectangle of a rotated rectangle is that rectangle.

#include "core/convex_hull_2d.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace {

using esf::detail::Vec2;

/// Vertices of the hull by brute force: p is one when some edge (p, q) has every point on its
/// left and none on the line beyond the segment.
std::vector<Vec2> brute_force_vertices(const std::vector<Vec2>& points) {
    std::vector<Vec2> out;
    for (const Vec2& p : points) {
        bool vertex = false;
        for (const Vec2& q : points) {
            if (q == p) continue;
            bool all_left = true;
            for (const Vec2& r : points) {
                const double c = esf::detail::cross(p, q, r);
                if (c < 0.0) {
                    all_left = false;
                    break;
                }
                // On the line: must lie on the segment [p, q] or p is not a corner there.
                if (c == 0.0 && (r - p).dot(q - p) < 0.0f) {
                    all_left = false;
                    break;
                }
            }
            if (all_left) {
                vertex = true;
                break;
            }
        }
        if (vertex) out.push_back(p);
    }
    return out;
}

std::vector<Vec2> sorted(std::vector<Vec2> v) {
    std::sort(v.begin(), v.end(), [](const Vec2& a, const Vec2& b) {
        return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
}

TEST(ConvexHull2d, VerticesMatchBruteForce) {
    std::mt19937 rng(5);
    std::normal_distribution<float> g(0.0f, 1.0f);
    for (int trial = 0; trial < 20; ++trial) {
        std::vector<Vec2> points(60 + 20 * trial);
        for (Vec2& p : points) p = Vec2(g(rng), 0.3f * g(rng));
        const std::vector<Vec2> chain = esf::detail::monotone_chain(points);
        const std::vector<Vec2> filtered = esf::detail::convex_hull(points);
        EXPECT_EQ(sorted(chain), sorted(brute_force_vertices(points))) << trial;
        EXPECT_EQ(chain, filtered) << trial;
        // Counter-clockwise and strictly convex.
        for (std::size_t k = 0; k < chain.size(); ++k)
            EXPECT_GT(esf::detail::cross(chain[k], chain[(k + 1) % chain.size()],
                                         chain[(k + 2) % chain.size()]),
                      0.0);
        // Every point is inside; points beyond the extremes are not.
        for (const Vec2& p : points) EXPECT_TRUE(esf::detail::inside_convex(chain, p));
        float max_x = -1e9f;
        for (const Vec2& p : points) max_x = std::max(max_x, p.x());
        EXPECT_FALSE(esf::detail::inside_convex(chain, Vec2(max_x + 0.01f, 0.0f)));
    }
}

TEST(ConvexHull2d, InsideAgreesWithTheEdgeTests) {
    const std::vector<Vec2> hull =
        esf::detail::monotone_chain({{0, 0}, {4, 0}, {5, 2}, {3, 5}, {-1, 3}, {1, 1}, {2, 2}});
    ASSERT_EQ(hull.size(), 5u);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-2.0f, 6.0f);
    for (int i = 0; i < 2000; ++i) {
        const Vec2 q(u(rng), u(rng));
        bool inside = true;
        for (std::size_t k = 0; k < hull.size(); ++k)
            inside = inside && esf::detail::cross(hull[k], hull[(k + 1) % hull.size()], q) >= 0.0;
        EXPECT_EQ(esf::detail::inside_convex(hull, q), inside) << q.transpose();
    }
}

TEST(ConvexHull2d, RegionAgreesWithInsideConvexEverywhere) {
    // Random hulls, from thin to round; points uniform over and around the bounding box, on the
    // vertices, on the edges' midpoints and just beside them.
    std::mt19937 rng(13);
    std::normal_distribution<float> g(0.0f, 1.0f);
    for (int trial = 0; trial < 12; ++trial) {
        std::vector<Vec2> points(30 + 40 * trial);
        const float aspect = 0.05f + 0.1f * static_cast<float>(trial);
        for (Vec2& p : points) p = Vec2(3.0f * g(rng), aspect * g(rng));
        const std::vector<Vec2> hull = esf::detail::monotone_chain(points);
        ASSERT_GE(hull.size(), 3u);
        const esf::detail::ConvexRegion region(hull);
        EXPECT_EQ(region.polygon(), hull);
        std::vector<Vec2> queries;
        std::uniform_real_distribution<float> ux(-12.0f, 12.0f), uy(-4.0f * aspect, 4.0f * aspect);
        for (int i = 0; i < 4000; ++i) queries.emplace_back(ux(rng), uy(rng));
        for (std::size_t k = 0; k < hull.size(); ++k) {
            const Vec2 mid = 0.5f * (hull[k] + hull[(k + 1) % hull.size()]);
            queries.push_back(hull[k]);
            queries.push_back(mid);
            for (const float e : {1e-6f, 1e-4f})
                for (const Vec2& d : {Vec2(e, 0.0f), Vec2(-e, 0.0f), Vec2(0.0f, e), Vec2(0.0f, -e)})
                    queries.push_back(mid + d);
        }
        std::size_t inside = 0;
        for (const Vec2& q : queries) {
            const bool want = esf::detail::inside_convex(hull, q);
            inside += want;
            EXPECT_EQ(region.contains(q), want) << trial << ": " << q.transpose();
        }
        EXPECT_GT(inside, queries.size() / 10) << trial;  // the test covers both answers
    }
}

TEST(ConvexHull2d, RegionWithAMarginIsTheRoundedOffset) {
    // The unit square, counter-clockwise, with a margin of 0.1: beside an edge the offset is
    // 0.1 wide; at a corner it is rounded (the diagonal reaches 0.1, not 0.1 sqrt 2).
    const esf::detail::ConvexRegion square({{0, 0}, {1, 0}, {1, 1}, {0, 1}});
    using V = esf::detail::Vec2;
    EXPECT_TRUE(square.contains(V(0.5f, 0.5f), 0.1f));
    EXPECT_TRUE(square.contains(V(1.09f, 0.5f), 0.1f));
    EXPECT_FALSE(square.contains(V(1.09f, 0.5f)));
    EXPECT_FALSE(square.contains(V(1.11f, 0.5f), 0.1f));
    EXPECT_TRUE(square.contains(V(0.5f, -0.09f), 0.1f));
    EXPECT_TRUE(square.contains(V(1.06f, 1.06f), 0.1f));   // 0.085 from the corner
    EXPECT_FALSE(square.contains(V(1.08f, 1.08f), 0.1f));  // 0.113 from the corner
    EXPECT_FALSE(square.contains(V(-0.09f, 0.5f), 0.0f));
    EXPECT_FALSE(square.contains(V(5.0f, 5.0f), 0.1f));
}

TEST(ConvexHull2d, SmallestRectangleOfARotatedRectangle) {
    const float angle = 0.4f, length = 3.0f, width = 1.25f;
    const Vec2 a(std::cos(angle), std::sin(angle)), b(-a.y(), a.x());
    std::vector<Vec2> points;
    for (int i = 0; i <= 10; ++i)
        for (int j = 0; j <= 10; ++j)
            points.push_back(0.1f * static_cast<float>(i) * length * a +
                             0.1f * static_cast<float>(j) * width * b + Vec2(2.0f, -1.0f));
    const esf::detail::Rectangle r =
        esf::detail::min_area_rectangle(esf::detail::convex_hull(points));
    EXPECT_NEAR(r.length, length, 1e-4f);
    EXPECT_NEAR(r.width, width, 1e-4f);
    EXPECT_NEAR(std::abs(r.length_axis.dot(a)), 1.0f, 1e-5f);
}

}  // namespace
