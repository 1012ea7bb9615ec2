#pragma once
// Internal: the random triangles of the ESF descriptor (Sec. III-C) and their ten histograms.
//
// The fast sampler draws attempts in blocks of 16, one per lane of 16 xoshiro128++ streams
// (seeded from the one 64-bit seed by SplitMix64): attempt 16 b + l takes three draws of stream
// l. The AVX-512 and AVX2 kernels and the portable code perform the same float operations in the
// same order, so both give the same triangles, bit for bit, on every machine.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/simd.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"

namespace esf::detail {

inline constexpr int kTopBin = kEsfBins - 1;  // 63

/// Lanes of the fast sampler's blocks, one per lane of an AVX-512 vector: 16 points per step of
/// the per-point passes, 16 attempts (one per stream) per block of the sampler, 16 triangles per
/// block of the histograms.
inline constexpr int kLanes = 16;

/// PCL's pcl_round(float) for a histogram position x >= 0: floor(x + 0.5f) in float (not
/// round(): 0.49999997f gives 1), by truncation.
inline int round_bin(float x) { return static_cast<int>(x + 0.5f); }

/// A point of the fast sampler: scaled coordinates and its cell (pack_cell()).
struct alignas(16) PackedPoint {
    float x, y, z;
    std::uint32_t cell;
};

/// Accepted triangles, structure of arrays. Line k of triangle t (k = 0: p1p2, 1: p1p3,
/// 2: p2p3) is entry k * samples + t of the per-line arrays.
struct TriangleSet {
    std::size_t samples = 0;
    std::vector<std::uint32_t> angle_bins;  // A3 bins at p1, p3, p2: b0 | b1 << 8 | b2 << 16
    std::vector<float> d2;                  // per line: its length in grid units
    std::vector<float> d3;                  // per triangle: sqrt(area)
    std::vector<std::uint32_t> line_start, line_end;  // per line: cells
    float max_d2 = 0.0f, max_d3 = 0.0f;

    void resize(std::size_t count);
};

/// Outcome of sample_triangles_fast().
struct SampleCount {
    std::size_t accepted = 0;
    std::size_t attempts = 0;
};

/// Draws triangles from `count` points (plus one readable padding point after them) until
/// `triangles.samples` are accepted or `max_attempts` are spent. A triple is rejected when two
/// indices coincide or its Heron product s(s-a)(s-b)(s-c) is at most `min_heron`.
SampleCount sample_triangles_fast(const PackedPoint* points, std::uint32_t count,
                                  std::uint64_t seed, std::size_t max_attempts, float min_heron,
                                  SimdLevel simd, TriangleSet& triangles);

/// acos(c) for c in [0, 1] (larger values count as 1) from a polynomial (Abramowitz & Stegun
/// 4.4.46, error 2e-8): the fast sampler's angles.
float fast_acos(float c);

/// The fast sampler's third angle. A3 takes each angle of a triangle folded into [0, pi/2]
/// (acos of |cos|). Of a triangle's three angles at most one is obtuse, so the folded angle at
/// p2 follows from the folded angles at p1 and p3 without a third acos; n1, n3 and n2 have the
/// signs of the cosines at p1, p3 and p2 (negative: obtuse there).
float third_angle(float angle1, float angle3, float n1, float n3, float n2);

/// The fast sampler's A3 bins of a triangle with sides a = |p1p2|, b = |p1p3|, c = |p2p3|, packed
/// as TriangleSet::angle_bins: the cosines by the law of cosines (cos at p1 =
/// (a^2 + b^2 - c^2) / 2ab), two angles by fast_acos(), the third by third_angle().
std::uint32_t triangle_angle_bins(float a, float b, float c);

/// A3 bin of a folded angle: round(angle / (pi/2) * 63), at most 63.
int angle_bin(float angle);

/// o[i] / v[i] for whole numbers 0 <= o[i] <= 64 and 1 <= v[i] <= 64 (a line's occupied and
/// visited cells), as the AVX-512 histogram kernel forms them without a division; it must equal
/// the rounded division. Needs AVX-512 (avx512_available()).
void small_ratios_avx512(const std::uint32_t* o, const std::uint32_t* v, float* out,
                         std::size_t count);

/// The ten histograms as integer counts (A3 counts are weighted by the visited cells of the
/// line opposite to the angle), from the triangles and the occupied / visited cells of their
/// lines. `pcl_division`: bin D2 and D3 values as the reference does (d / max * 63) rather than
/// by multiplying with 63 / max.
using EsfCounts = std::array<std::array<std::uint32_t, kEsfBins>, kEsfBlocks>;
EsfCounts histogram_triangles(const TriangleSet& triangles, const std::uint32_t* occupied,
                              const std::uint8_t* visited, bool pcl_division, SimdLevel simd);

}  // namespace esf::detail
