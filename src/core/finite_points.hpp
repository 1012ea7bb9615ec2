#pragma once
// Internal: dropping the points with a NaN or infinite coordinate, with an AVX-512 kernel where
// the CPU has one (the same points, in the same order, on every kernel set).

#include <Eigen/Core>
#include <cstddef>
#include <span>
#include <vector>

#include "core/simd.hpp"

namespace esf::detail {

/// The finite points (no NaN or infinite coordinate), in order, into `finite` (replaced; its
/// memory is reused); returns how many were dropped. The same points whatever `simd` says.
std::size_t keep_finite_points(std::span<const Eigen::Vector3f> points, SimdLevel simd,
                               std::vector<Eigen::Vector3f>& finite);

/// The same in place: `points` keeps its finite points, in order; returns how many were dropped.
std::size_t keep_finite_in_place(std::vector<Eigen::Vector3f>& points, SimdLevel simd);

}  // namespace esf::detail
