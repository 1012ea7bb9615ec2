// Euclidean clustering on the hash grid against brute force: the same partition as linking
// every pair of points at most the tolerance apart, in order of first appearance.

#include "segmentation/euclidean_clusters.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "core/disjoint_sets.hpp"

namespace {

std::vector<std::uint32_t> brute_force(const std::vector<Eigen::Vector3f>& points,
                                       float tolerance) {
    esf::DisjointSets sets(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        for (std::size_t j = i + 1; j < points.size(); ++j)
            if ((points[i] - points[j]).squaredNorm() <= tolerance * tolerance)
                sets.unite(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
    std::vector<std::uint32_t> label(points.size());
    std::vector<std::int64_t> number(points.size(), -1);
    std::uint32_t next = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const std::uint32_t root = sets.find(static_cast<std::uint32_t>(i));
        if (number[root] < 0) number[root] = next++;
        label[i] = static_cast<std::uint32_t>(number[root]);
    }
    return label;
}

TEST(EuclideanClusters, SamePartitionAsBruteForce) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    for (const float tolerance : {0.01f, 0.03f, 0.08f}) {
        std::vector<Eigen::Vector3f> points(1500);
        for (auto& p : points) p = Eigen::Vector3f(u(rng), u(rng), 0.2f * u(rng));
        EXPECT_EQ(esf::detail::euclidean_components(points, tolerance),
                  brute_force(points, tolerance))
            << tolerance;
    }
}

TEST(EuclideanClusters, PairsJustInsideAndOutsideTheTolerance) {
    const float t = 0.02f;
    const std::vector<Eigen::Vector3f> points = {
        {0, 0, 0}, {0.0190f, 0, 0}, {0.0380f, 0, 0}, {0.0600f, 0, 0}, {0.0600f, 0.0210f, 0}};
    EXPECT_EQ(esf::detail::euclidean_components(points, t),
              (std::vector<std::uint32_t>{0, 0, 0, 1, 2}));
}

TEST(EuclideanClusters, GridLimits) {
    EXPECT_TRUE(esf::detail::fits_clustering_grid({1.0f, -2.0f, 3.0f}, 0.02f));
    EXPECT_FALSE(esf::detail::fits_clustering_grid({1e6f, 0.0f, 0.0f}, 0.02f));
}

}  // namespace
