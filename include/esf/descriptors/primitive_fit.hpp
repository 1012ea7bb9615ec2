#pragma once
// Which simple solid explains a partial view better: a cylinder (side and lids) or a box (up to
// three mutually orthogonal faces). The outline and the curved side tell a can from a box where
// the distributions of ESF and the surface angles look alike (lids, flat tins, boxes seen on a
// corner), so esf-angles carries the contrast as one more block.
//
//   cells     the surface cells of esf-angles (surface_angles.hpp): side h = max(7 mm,
//             diagonal / 64), normals from 3 x 3 x 3 neighbourhoods, turned towards the sensor
//   cylinder  RANSAC over pairs of cells: the axis is the cross product of their normals, the
//             centre where their normal lines meet in the plane across the axis; a cell is on
//             the side when it lies within tol of the radius with its normal within 25 degrees of
//             the radial direction, on a lid when its normal is within 25 degrees of the axis
//             inside the radius. The best hypothesis is refined three times (the axis from the
//             side and lid normals, the centre and radius by a geometric circle fit)
//   box       three planes found greedily by RANSAC, each orthogonal to those before (within
//             about 12 degrees); a cell belongs to a plane within tol with its normal within 25
//             degrees of the plane's
//   shares    cylinder, box: the share of the cells each solid explains; tol = max(4 mm, 0.6 h)
//
// Measured on the real segmented views (`real/labels.csv`, tests/descriptors/primitive_fit_test):
// cylinder > box for 62 of 63 cans and box >= cylinder for 124 of 141 boxes. Seeded: the same
// cloud and seed give the same fit.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "esf/descriptors/surface_angles.hpp"

namespace esf {

struct PrimitiveFitOptions {
    /// Smallest cell side (metres): the surface angles' cells.
    double cell_size = SurfaceAngleOptions{}.cell_size;
    int iterations = 128;  ///< RANSAC hypotheses for the cylinder and for each box face
    /// Cells scoring each hypothesis (evenly spaced); the chosen solid is scored on all cells.
    std::size_t scored_cells = 256;
    std::uint64_t seed = 0;
};

struct PrimitiveFit {
    double cylinder = 0.0;  ///< share of the cells on the best cylinder's side and lids, [0, 1]
    double box = 0.0;       ///< share of the cells on the best box's faces, [0, 1]
    double radius = 0.0;    ///< the cylinder's, metres (0 when none was found)
    Eigen::Vector3d axis = Eigen::Vector3d::Zero();  ///< the cylinder's (sensor frame)
    std::size_t cells = 0;                           ///< cells with a normal
};

/// Fits both solids to a cloud (sensor frame; non-finite points dropped). Clouds with fewer than
/// 10 cells fit neither (both shares 0). Throws std::invalid_argument for fewer than 3 finite
/// points, a cell size that is not positive and finite, iterations < 1 or scored_cells < 1.
PrimitiveFit fit_primitives(std::span<const Eigen::Vector3f> points,
                            const PrimitiveFitOptions& options = {});

inline constexpr int kPrimitiveBins = 8;
using PrimitiveHistogram = std::array<float, kPrimitiveBins>;

/// The contrast cylinder - box in [-1, 1] as a histogram of kPrimitiveBins bins summing to 1:
/// split linearly between the two nearest bin centres, so that the L1 distance of two
/// histograms grows with the difference of their contrasts up to two bins apart.
PrimitiveHistogram primitive_histogram(const PrimitiveFit& fit);

/// The name of that histogram's block in a descriptor (DescriptorInfo::block_names).
inline constexpr const char* kPrimitiveBlockName = "cylinder-box";

/// The contrast a histogram of primitive_histogram() stands for (a block of a stored signature
/// may be scaled: only the shares of its bins count): the mean of the bin centres weighted by
/// the bins, so the contrast itself within [-1 + w / 2, 1 - w / 2] (w the bin width). NaN for a
/// histogram of another size, or with no positive sum.
double primitive_contrast(std::span<const float> histogram);

}  // namespace esf
