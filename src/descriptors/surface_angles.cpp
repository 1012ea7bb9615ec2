#include "esf/descriptors/surface_angles.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "descriptors/cell_features.hpp"

namespace esf {
namespace {

/// Bin of a value in [lo, hi] among `bins` equal bins (the top edge goes to the last bin).
int bin_of(double value, double lo, double hi, int bins) {
    const double t = (value - lo) / (hi - lo) * bins;
    return std::clamp(static_cast<int>(std::floor(t)), 0, bins - 1);
}

}  // namespace

SurfaceAngleHistograms compute_surface_angles(std::span<const Eigen::Vector3f> points,
                                              const SurfaceAngleOptions& options) {
    return detail::surface_angles(
        detail::surface_cells(points, options.cell_size, "surface angles"));
}

namespace detail {

SurfaceAngleHistograms surface_angles(const SurfaceCells& cells) {
    const std::vector<SurfaceCell>& surfels = cells.cells;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    Eigen::Vector3d mean_normal = Eigen::Vector3d::Zero();
    for (const SurfaceCell& s : surfels) {
        centre += s.position;
        mean_normal += s.normal;
    }
    centre /= static_cast<double>(surfels.size());
    const Eigen::Vector3d view =
        centre.norm() > 0.0 ? Eigen::Vector3d(-centre.normalized()) : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d u = mean_normal.norm() > 1e-9 ? mean_normal.normalized() : view;
    double max_distance = 0.0;
    for (const SurfaceCell& s : surfels)
        max_distance = std::max(max_distance, (s.position - centre).norm());

    std::array<double, kSurfaceAngleSize> counts{};
    constexpr int kAlpha = 0, kPhi = kSurfaceAngleBins, kTheta = 2 * kSurfaceAngleBins,
                  kDistance = 3 * kSurfaceAngleBins, kBeta = 4 * kSurfaceAngleBins,
                  kSigma = kBeta + kSurfaceViewpointBins;
    constexpr double kPi = std::numbers::pi;
    std::size_t framed = 0;
    for (const SurfaceCell& s : surfels) {
        const Eigen::Vector3d& n = s.normal;
        counts[static_cast<std::size_t>(
            kBeta + bin_of(n.dot(view), -1.0, 1.0, kSurfaceViewpointBins))] += 1.0;
        counts[static_cast<std::size_t>(
            kSigma + bin_of(s.variation, 0.0, 1.0 / 3.0, kSurfaceVariationBins))] += 1.0;
        const Eigen::Vector3d d = s.position - centre;
        const double distance = d.norm();
        Eigen::Vector3d w1 = d.cross(u);
        if (!(distance > 0.0) || !(w1.norm() > 1e-12 * distance)) continue;
        w1.normalize();
        const Eigen::Vector3d w2 = u.cross(w1);
        const double alpha = w1.dot(n);
        const double phi = u.dot(d) / distance;
        const double theta = std::atan2(w2.dot(n), u.dot(n));
        counts[static_cast<std::size_t>(kAlpha + bin_of(alpha, -1.0, 1.0, kSurfaceAngleBins))] +=
            1.0;
        counts[static_cast<std::size_t>(kPhi + bin_of(phi, -1.0, 1.0, kSurfaceAngleBins))] += 1.0;
        counts[static_cast<std::size_t>(kTheta + bin_of(theta, -kPi, kPi, kSurfaceAngleBins))] +=
            1.0;
        counts[static_cast<std::size_t>(
            kDistance + bin_of(distance / max_distance, 0.0, 1.0, kSurfaceAngleBins))] += 1.0;
        ++framed;
    }
    SurfaceAngleHistograms out{};
    const std::array<int, kSurfaceAngleBlocks + 1> edges = {
        kAlpha, kPhi, kTheta, kDistance, kBeta, kSigma, kSurfaceAngleSize};
    for (std::size_t b = 0; b < kSurfaceAngleBlocks; ++b) {
        const double total =
            b < 4 ? static_cast<double>(framed) : static_cast<double>(surfels.size());
        if (!(total > 0.0)) continue;  // every cell at the centre: leave the block empty
        for (int i = edges[b]; i < edges[b + 1]; ++i)
            out[static_cast<std::size_t>(i)] =
                static_cast<float>(counts[static_cast<std::size_t>(i)] / total);
    }
    return out;
}

}  // namespace detail

}  // namespace esf
