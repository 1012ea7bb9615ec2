#pragma once
// Internal: the per-point passes' lane sums and their AVX2 (esf_points_avx2.cpp) and AVX-512
// (esf_points_avx512.cpp) kernels; the portable code and the choice of kernel are in
// esf_points.cpp. Every file is compiled with -ffp-contract=off, so that all of them round
// alike.

#include <cstddef>
#include <cstdint>

#include "descriptors/esf/esf_points.hpp"

namespace esf::detail {

/// `Count` lane-wise partial sums: point i adds to lane i % 16; totals reduce in lane order.
template <int Count>
struct LaneSumsOf {
    double v[Count][kLanes] = {};
    double total(int k) const {
        double sum = 0.0;
        for (double x : v[k]) sum += x;
        return sum;
    }
};

/// Sums of x, y and z.
using LaneSums = LaneSumsOf<3>;
/// Moments of the scaled points: x, y, z, xx, xy, xz, yy, yz, zz.
using LaneMoments = LaneSumsOf<9>;

/// The same moments summed in float (the AVX-512 kernel's first look).
struct FloatMoments {
    alignas(64) float v[9][kLanes] = {};
    double total(int k) const {
        double sum = 0.0;
        for (float x : v[k]) sum += static_cast<double>(x);
        return sum;
    }
};

// The kernels of each instruction set, on the first `blocks` x 16 points p (x, y, z
// interleaved); the callers check the CPU first (core/simd.hpp).

/// Sums of the points (AVX-512).
void sum_avx512(const float* p, std::size_t blocks, LaneSums& sums);
/// The largest squared distance of a point from the centre of `t` (AVX-512).
double radius2_avx512(const float* p, std::size_t blocks, const Normalisation& t);
/// Scales, packs and voxelises the points (AVX-512); the moments go to `moments`, and to
/// `cells` each cell that differs from the previous point's (a scan's neighbouring points often
/// share a cell: the grid then takes one write per run). Returns how many cells were written
/// (`cells` has room for 16 more than the points).
std::size_t voxelise_avx512(const float* p, std::size_t blocks, const Normalisation& t, int half,
                            PackedPoint* packed, std::uint32_t* cells, FloatMoments& moments);

/// sum_avx512() with AVX2.
void sum_avx2(const float* p, std::size_t blocks, LaneSums& sums);
/// radius2_avx512() with AVX2.
double radius2_avx2(const float* p, std::size_t blocks, const Normalisation& t);
/// Scales, packs and voxelises the points (AVX2); their cells go to `cells` (one per point),
/// the moments to `moments`.
void voxelise_avx2(const float* p, std::size_t blocks, const Normalisation& t, int half,
                   PackedPoint* packed, std::uint32_t* cells, LaneMoments& moments);

}  // namespace esf::detail
