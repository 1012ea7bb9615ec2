#pragma once
// The dominant plane of a table scene (segmentation.hpp, steps 1 and 2): RANSAC on a subsample
// with the adaptive stopping rule, then a least-squares refit to the inliers.

#include <Eigen/Core>
#include <cstddef>
#include <span>
#include <utility>

#include "esf/segmentation/segmentation.hpp"

namespace esf::detail {

/// A plane n . p + d = 0 and the samples within the distance of it (0 for a degenerate sample).
struct PlaneHypothesis {
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();
    float d = 0.0f;
    std::size_t inliers = 0;
};

/// RANSAC (Fischler & Bolles 1981) over `samples`: options.plane_iterations hypotheses at most,
/// fewer by the adaptive stopping rule for options.plane_confidence; hypothesis i draws from
/// (options.seed, i) alone, so the result is the same for any thread count.
PlaneHypothesis ransac_plane(std::span<const Eigen::Vector3f> samples,
                             const SegmentationOptions& options);

/// Least-squares plane through the points within `distance` of `plane` (normal = eigenvector
/// of the smallest eigenvalue of their covariance, on the side of plane.normal). Returns the
/// input plane when fewer than 3 points are that close.
Plane refit_plane(std::span<const Eigen::Vector3f> points, const Plane& plane, float distance);

/// `plane` with its normal turned, if need be, to the side of `viewpoint` (which decides "above").
Plane facing(Plane plane, const Eigen::Vector3f& viewpoint);

/// Orthonormal basis (u, w) of the plane with normal `normal` (unit), u x w = normal: the table
/// plane's coordinates.
std::pair<Eigen::Vector3f, Eigen::Vector3f> plane_basis(const Eigen::Vector3f& normal);

}  // namespace esf::detail
