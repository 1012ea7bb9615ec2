#pragma once
// Euclidean clustering on a hash grid (segmentation.hpp, grouping kEuclidean): the connected
// components of the graph linking points at most a tolerance apart, without a k-d tree.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace esf::detail {

/// Whether a point lies within the clustering grid for `tolerance` (2^20 cells of tolerance /
/// sqrt(3) from the origin per axis); euclidean_components() needs every point to.
bool fits_clustering_grid(const Eigen::Vector3f& p, float tolerance);

/// Connected components of the graph linking points at most `tolerance` apart: exactly the
/// clusters of PCL's EuclideanClusterExtraction (Rusu 2009, Sec. 4.2). Returns the component
/// of each point, numbered in order of first appearance.
std::vector<std::uint32_t> euclidean_components(std::span<const Eigen::Vector3f> points,
                                                float tolerance);

}  // namespace esf::detail
