#pragma once
// The point cloud type used across esf, and removal of non-finite points.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace esf {

/// Points in metres (or any unit: ESF is scale invariant), x/y/z in the sensor or model frame.
using Points = std::vector<Eigen::Vector3f>;

/// A cloud as read from a file. `width` x `height` is the organised layout (height 1 when
/// unorganised); `labels` is empty or holds one per point (e.g. the `label` field of a PCD).
struct PointCloud {
    Points points;
    std::uint32_t width = 0;
    std::uint32_t height = 1;
    std::vector<std::uint32_t> labels;
    /// Empty or one colour per point, packed 0x00RRGGBB as PCL does (written by write_pcd).
    std::vector<std::uint32_t> rgb;

    bool organised() const { return height > 1; }
};

/// Result of drop_non_finite(): the finite points, in input order, and how many were dropped.
struct FinitePoints {
    Points points;
    std::size_t dropped = 0;
};

/// Keeps the points whose three coordinates are finite (NaN and +-inf are dropped).
FinitePoints drop_non_finite(std::span<const Eigen::Vector3f> points);

/// The same into `finite` (replaced; its memory is reused): returns how many were dropped.
std::size_t drop_non_finite(std::span<const Eigen::Vector3f> points, Points& finite);

}  // namespace esf
