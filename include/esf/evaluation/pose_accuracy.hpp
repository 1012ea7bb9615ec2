#pragma once
// Pose accuracy as the BOP benchmark measures it for objects with or without symmetries
// (Hodan et al., "BOP: Benchmark for 6D Object Pose Estimation", ECCV 2018): ADD-S, the mean
// distance from each model point under the true pose to the nearest model point under the
// estimated pose, and the share of objects whose ADD-S is below 10 % of the model's diameter;
// and, for models without a symmetry, the rotation error (the angle between the two rotations).

#include <Eigen/Core>
#include <cstddef>
#include <span>

#include "esf/core/point_cloud.hpp"
#include "esf/mesh/mesh.hpp"

namespace esf {

/// Fraction of the model's diameter a pose may be off by (ADD-S) and still count as right.
inline constexpr double kAddSThreshold = 0.1;

/// ADD-S of `model_points` (the mesh file's coordinates) under `truth` and `estimate` (both mesh
/// file -> camera, scale included): metres. Exact nearest neighbours (O(n^2): a few hundred
/// points). Throws std::invalid_argument for no points or non-finite poses.
double add_s(std::span<const Eigen::Vector3f> model_points, const Eigen::Matrix4d& truth,
             const Eigen::Matrix4d& estimate);

/// The diameter of `model_points` under `truth` (largest distance between two points, metres).
double posed_diameter(std::span<const Eigen::Vector3f> model_points, const Eigen::Matrix4d& truth);

/// The angle in degrees, in [0, 180], of the rotation that takes `truth`'s rotation to
/// `estimate`'s (both mesh file -> camera: a rotation times a positive scale, which is removed).
/// Throws std::invalid_argument for a pose that is not finite or whose 3x3 block has no positive
/// determinant.
double rotation_error_degrees(const Eigen::Matrix4d& truth, const Eigen::Matrix4d& estimate);

/// Symmetry turns are tried in steps of 360 / n degrees for these n, about each principal axis
/// of the model's surface and each axis of the mesh's frame, all through the surface's centre.
inline constexpr int kSymmetryOrders[] = {2, 3, 4, 5, 6, 8, 12};
/// Surface samples of each of the two samplings has_symmetry compares.
inline constexpr std::size_t kSymmetrySamples = 1500;
/// A turn is a symmetry where the kSymmetryQuantile quantile of the distances from the turned
/// samples of one sampling to the nearest sample of the other is at most kSymmetrySlack times
/// that quantile without the turn (two samplings of one surface). On the shared meshes: cans,
/// bottles, boxes and cubes 0.98 to 1.13; a clamp 1.57, a knife 1.85, a figurine 2.0, a banana
/// 2.3, a mug with its handle 2.7.
inline constexpr double kSymmetryQuantile = 0.97;
inline constexpr double kSymmetrySlack = 1.3;

/// Whether some turn of the model about an axis through its surface's centre maps its surface
/// onto itself (kSymmetryOrders, kSymmetrySlack): a cylinder, a box and a ball have one, a mug
/// with its handle does not. Where a model has one, a rotation error says nothing about the pose
/// (ADD-S does). Seeded: the same mesh always gives the same answer. Throws
/// std::invalid_argument for a mesh sample_model_surface refuses.
bool has_symmetry(const Mesh& mesh);

}  // namespace esf
