#pragma once
// Internal: the per-point passes of the fast ESF sampler. The points are centred and scaled so
// that the farthest lies at radius `half` (Sec. III-A), and their cells are set in the voxel
// grid (Sec. III-B). Sums run in 16 lane-wise partial sums of doubles (point i in lane i % 16),
// reduced in lane order, so the AVX-512 and AVX2 kernels and the portable code agree bit for bit.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "core/finite_points.hpp"
#include "core/simd.hpp"
#include "descriptors/esf/esf_trace.hpp"
#include "descriptors/esf/esf_triangles.hpp"

namespace esf::detail {

/// Cell index of a scaled coordinate (reference: floor(v) + h if v < 0, else ceil(v) + h - 1),
/// clamped to the grid (the reference reads outside it when rounding puts a point at 32.00001).
/// |v| <= 32, so floor and ceil come from truncation.
inline std::uint32_t cell_of(float v, int half) {
    const int truncated = static_cast<int>(v);
    const bool fractional = static_cast<float>(truncated) != v;
    const int c = v < 0.0f ? truncated - fractional + half : truncated + fractional + half - 1;
    return static_cast<std::uint32_t>(c < 0 ? 0 : c > 2 * half - 1 ? 2 * half - 1 : c);
}

/// p -> (p - centre) * scale, in double, rounded to float.
struct Normalisation {
    double cx = 0.0, cy = 0.0, cz = 0.0, scale = 0.0;
};

enum class NormaliseOutcome {
    kNormalised,
    kCoincident,  // all points coincide
    kNonFinite,   // some coordinate is NaN or infinite (a sum of doubles is finite iff its terms
                  // are)
};

/// Centre and scale of the points; `out` is valid when kNormalised.
NormaliseOutcome normalise_points(std::span<const Eigen::Vector3f> points, int half, SimdLevel simd,
                                  Normalisation& out);

/// Whether points with this covariance lie on one line: the second largest eigenvalue is at
/// most 1e-10 of the largest.
bool on_one_line(const Eigen::Matrix3d& covariance);

/// Scales every point, stores it with its cell in `packed` (plus one zero padding point), and
/// sets the cells in `grid` (not cleared first); `cells` is scratch for the cells to set. Returns
/// whether the scaled points lie on one line: on_one_line() of their covariance, its moments summed
/// in double. The AVX-512 kernel first sums them in float; when that covariance's second eigenvalue
/// is at least a fifth of the largest, far beyond the float sums' error, the answer is no without
/// the doubles.
bool voxelise_points(std::span<const Eigen::Vector3f> points, const Normalisation& t, int half,
                     SimdLevel simd, std::vector<PackedPoint>& packed,
                     std::vector<std::uint32_t>& cells, VoxelGrid& grid);

}  // namespace esf::detail
