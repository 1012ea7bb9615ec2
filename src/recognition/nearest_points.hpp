#pragma once
// The nearest of a fixed set of points to a query, within a radius (internal to verification).
// A uniform grid of cubic cells, its points sorted by cell, as KISS-ICP's voxel map: the radii
// of verification are a few cell sizes or less, so a query reads a handful of cells where a
// k-d tree descends and backtracks (BENCHMARKS.md, "Nearest points by a grid").

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "esf/core/point_cloud.hpp"

namespace esf::detail {

class NearestPoints {
  public:
    /// Cells of `cell` metres (> 0, finite), made larger where the points' box would otherwise
    /// need more than 8 cells a point (4,096 for a few points): memory stays of the order of the
    /// points'. Points that are not finite are never found.
    NearestPoints(Points points, float cell);

    /// The index of the point nearest to `q` with a squared distance of at most
    /// `radius_squared`, and that squared distance (float, summed x, y, z in that order);
    /// false when there is none. A `hint` (an index, or anything out of range for none) is
    /// tried first; a point found later replaces it only when strictly nearer. Among points at
    /// exactly the same distance the first tried wins.
    bool nearest_within(const Eigen::Vector3f& q, float radius_squared, std::size_t hint,
                        std::size_t& index, float& squared) const;

    const Points& points() const { return points_; }

  private:
    Points points_;
    // The finite points sorted by cell, coordinate by coordinate (each padded by kPadding
    // zeros, so that a block of four may be read past the last point), and their indices.
    static constexpr std::size_t kPadding = 3;
    std::vector<float> xs_, ys_, zs_;
    std::vector<std::uint32_t> sorted_index_;
    std::vector<std::uint32_t> cell_start_;  // cells + 1 offsets into the sorted points
    Eigen::Vector3f origin_ = Eigen::Vector3f::Zero();
    float inverse_cell_ = 1.0f;
    int cells_[3] = {0, 0, 0};  // x, y, z
};

}  // namespace esf::detail
