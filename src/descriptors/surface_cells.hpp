#pragma once
// The surface cells shared by the normal-based blocks of esf-angles (surface angles, primitive
// fit): the points fall into cubic cells of side h = max(cell_size, diagonal / 64); each cell
// with enough surface around it gets a normal, the least-variance direction of the points of
// its 3 x 3 x 3 neighbourhood turned towards the sensor (the origin), and that neighbourhood's
// surface variation lambda_0 / (lambda_0 + lambda_1 + lambda_2).

#include <Eigen/Core>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace esf::detail {

struct SurfaceCell {
    Eigen::Vector3d position;  ///< centroid of the cell's points, sensor frame
    Eigen::Vector3d normal;    ///< unit, towards the sensor
    double variation = 0.0;    ///< [0, 1/3]
};

struct SurfaceCells {
    std::vector<SurfaceCell> cells;  ///< in order of first occupation
    double cell_size = 0.0;          ///< h, metres
    std::size_t finite_points = 0;
};

/// The cells of a cloud (non-finite points dropped). Throws std::invalid_argument, its message
/// starting with `what`, for fewer than 3 finite points, a cell size that is not positive and
/// finite, or a cloud where no cell gets a normal.
SurfaceCells surface_cells(std::span<const Eigen::Vector3f> points, double cell_size,
                           const std::string& what);

}  // namespace esf::detail
