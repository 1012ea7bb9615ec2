#pragma once
// The normal-based blocks of esf-angles computed on surface cells already at hand, so that the
// descriptor finds the cells once for the surface angles and the primitive fit.

#include <span>

#include "descriptors/surface_cells.hpp"
#include "esf/descriptors/primitive_fit.hpp"
#include "esf/descriptors/surface_angles.hpp"

namespace esf::detail {

/// compute_surface_angles() on the cells of surface_cells().
SurfaceAngleHistograms surface_angles(const SurfaceCells& cells);

/// fit_primitives() on the cells of surface_cells(). Throws std::invalid_argument for
/// iterations < 1 or scored_cells < 1.
PrimitiveFit fit_primitives(std::span<const SurfaceCell> cells, double cell_size,
                            const PrimitiveFitOptions& options);

}  // namespace esf::detail
