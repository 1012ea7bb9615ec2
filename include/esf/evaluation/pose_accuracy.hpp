#pragma once
// Pose accuracy as the BOP benchmark measures it for objects with or without symmetries
// (Hodan et al., "BOP: Benchmark for 6D Object Pose Estimation", ECCV 2018): ADD-S, the mean
// distance from each model point under the true pose to the nearest model point under the
// estimated pose, and the share of objects whose ADD-S is below 10 % of the model's diameter.

#include <Eigen/Core>
#include <span>

#include "esf/core/point_cloud.hpp"

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

}  // namespace esf
