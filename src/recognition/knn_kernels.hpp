#pragma once
// Distance kernels of the k-NN index (internal): portable C++ (knn_kernels.cpp) and, chosen at
// run time, AVX2 (knn_kernels_avx2.cpp) and AVX-512 (knn_kernels_avx512.cpp) versions. Every
// file is compiled with -ffp-contract=off so that no multiply-add is fused.

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "esf/core/kernels.hpp"

namespace esf::detail {

/// Canonical weighted L1: lane i % 8 accumulates w_i * |a_i - b_i| (differences and products
/// in double) in increasing i; the lanes are combined as ((l0+l4)+(l2+l6))+((l1+l5)+(l3+l7)).
/// Every kernel returns bit-identical values.
///
/// `limit`: after every kExactCheck elements the lanes accumulated so far are combined the same
/// way; when that partial sum exceeds `limit` the kernel stops and returns it. The terms are
/// never negative and rounding to nearest is monotone, so the full distance is then larger than
/// `limit` too; a returned value <= limit is the full distance, bit for bit. +infinity never
/// stops.
using ExactL1Fn = double (*)(const float* a, const float* b, const float* w, std::size_t n,
                             double limit);

/// Elements between two partial-sum checks of an exact kernel (a multiple of 8).
inline constexpr std::size_t kExactCheck = 128;

/// Lower bounds for `count` rows of `stride` bytes (a multiple of 16) starting at `rows`, with
/// `weight` padded with zeros to a multiple of 8 lanes (of 8 bytes):
///     bound_r = (unit * S_r - row_error[r]) - query_error,
///     S_r = sum over lanes l of weight[l] * sum_{j in l} |query_j - row_j|,
/// S_r taken exactly in 64-bit integers (it must stay below 2^52), so that every kernel returns
/// bit-identical values. Only the bounds that do not exceed `limit` are kept: they are written
/// in row order to `bound`, with their row numbers first_row + r to `row`, and the kernel
/// returns how many it wrote (at most `count`; all of them when `limit` is +infinity).
using SketchFn = std::size_t (*)(const std::uint8_t* rows, std::size_t count, std::size_t stride,
                                 const std::uint8_t* query, const std::uint32_t* weight,
                                 double unit, const double* row_error, double query_error,
                                 double limit, std::uint32_t first_row, double* bound,
                                 std::uint32_t* row);

struct KnnKernels {
    ExactL1Fn exact;
    SketchFn sketch;
};

/// The kernels of `kernels` (kBest resolves to best_kernels()); the CPU must support them
/// (kernels_supported()).
KnnKernels knn_kernels(Kernels kernels);

// The kernels of each instruction set.
double exact_avx2(const float* a, const float* b, const float* w, std::size_t n, double limit);
std::size_t sketch_avx2(const std::uint8_t* rows, std::size_t count, std::size_t stride,
                        const std::uint8_t* query, const std::uint32_t* weight, double unit,
                        const double* row_error, double query_error, double limit,
                        std::uint32_t first_row, double* bound, std::uint32_t* row);
double exact_avx512(const float* a, const float* b, const float* w, std::size_t n, double limit);
std::size_t sketch_avx512(const std::uint8_t* rows, std::size_t count, std::size_t stride,
                          const std::uint8_t* query, const std::uint32_t* weight, double unit,
                          const double* row_error, double query_error, double limit,
                          std::uint32_t first_row, double* bound, std::uint32_t* row);

/// The sketch kernels' output of a run of rows: bounds[i] (row first_row + i) for every bit i
/// set in `below` (the rows whose bound does not exceed the limit), appended to bound[kept] and
/// row[kept]; returns the new number kept.
inline std::size_t keep_rows(const double* bounds, unsigned below, std::uint32_t first_row,
                             std::size_t kept, double* bound, std::uint32_t* row) {
    for (; below != 0; below &= below - 1) {
        const auto i = static_cast<std::uint32_t>(__builtin_ctz(below));
        bound[kept] = bounds[i];
        row[kept] = first_row + i;
        ++kept;
    }
    return kept;
}

/// The fixed pairwise combination of the eight lanes shared by every exact kernel.
inline double combine_lanes(const double* lane) {
    return ((lane[0] + lane[4]) + (lane[2] + lane[6])) +
           ((lane[1] + lane[5]) + (lane[3] + lane[7]));
}

/// Adds the elements [begin, n) to their lanes (begin is a multiple of 8).
inline void exact_tail(const float* a, const float* b, const float* w, std::size_t begin,
                       std::size_t n, double* lane) {
    for (std::size_t i = begin; i < n; ++i)
        lane[i & 7] += static_cast<double>(w[i]) *
                       std::fabs(static_cast<double>(a[i]) - static_cast<double>(b[i]));
}

}  // namespace esf::detail
