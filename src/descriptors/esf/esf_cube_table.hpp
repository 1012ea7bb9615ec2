#pragma once
// Internal: what the SIMD line tracers share about the table of 3x3x3 cubes they look cells up
// in, three cells per look-up (esf_trace_avx512.cpp explains the closed form and the table;
// esf_cube_table.inl builds it). Entry j of the table (from kCubePad) holds the 3x3x3 cells
// j + dx + 64 dy + 4096 dz as bit dx + 3 dy + 9 dz.

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

#include "descriptors/esf/esf_voxel_grid.hpp"

namespace esf::detail {

inline constexpr std::int32_t kGridCells = kGridSide * kGridSide * kGridSide;
/// Entries before cell 0: anchors reach down to cell -(2 + 2 * 64 + 2 * 4096).
inline constexpr std::int32_t kCubePad = 8448;
inline constexpr int kCubeWordPad = kCubePad / 64;

/// 1 / (2L) for L = 1 .. 64 (the slopes of a line of L cells).
constexpr std::array<float, 64> half_per_cell_table() {
    std::array<float, 64> table{};
    for (int l = 1; l <= 64; ++l)
        table[static_cast<std::size_t>(l - 1)] = 0.5f / static_cast<float>(l);
    return table;
}
alignas(64) inline constexpr std::array<float, 64> kHalfPerCell = half_per_cell_table();

/// Calls f(i) for each set bit i of `bits` with from <= i < to.
template <typename F>
inline void for_each_bit(const std::uint64_t* bits, int from, int to, F&& f) {
    for (int chunk = from >> 6; from < to; ++chunk) {
        std::uint64_t m = bits[chunk] & (~std::uint64_t{0} << (from & 63));
        const int end = std::min(to, (chunk + 1) * 64);
        if (end < (chunk + 1) * 64) m &= (std::uint64_t{1} << (end & 63)) - 1;
        for (; m != 0; m &= m - 1) f(chunk * 64 + std::countr_zero(m));
        from = end;
    }
}

}  // namespace esf::detail
