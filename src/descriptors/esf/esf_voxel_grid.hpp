#pragma once
// Internal: the voxel grid of the ESF descriptor (Sec. III-B), a 64^3 bit array (32 KiB, cache
// resident): cell (x, y, z) is bit x | y << 6 | z << 12.

#include <array>
#include <cstdint>

#include "core/simd.hpp"

namespace esf::detail {

inline constexpr int kGridBits = 6;
inline constexpr int kGridSide = 1 << kGridBits;  // 64
inline constexpr int kGridWords = kGridSide * kGridSide * kGridSide / 64;

/// Cell index x | y << 6 | z << 12 of cell (x, y, z), each in [0, 63].
constexpr std::uint32_t pack_cell(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return x | (y << kGridBits) | (z << (2 * kGridBits));
}

struct alignas(64) VoxelGrid {
    using Words = std::array<std::uint64_t, kGridWords>;
    alignas(64) Words words{};

    void clear() { words.fill(0); }
    void set(std::uint32_t cell) { words[cell >> 6] |= std::uint64_t{1} << (cell & 63); }
    bool occupied(std::uint32_t cell) const { return (words[cell >> 6] >> (cell & 63)) & 1; }
    /// Marks the 26 neighbours of every set cell too (the one-cell dilation of the reference),
    /// clipped to the first `side` cells of each axis. `simd`: the widest kernels to use, the
    /// narrower where the CPU lacks them (the same bits on every level).
    void dilate(int side, SimdLevel simd = SimdLevel::kAvx512);
};

/// VoxelGrid::dilate() with AVX-512 (the same bits); needs avx512_available().
void dilate_avx512(VoxelGrid::Words& words, int side);
/// VoxelGrid::dilate() with AVX2 (the same bits); needs avx2_available().
void dilate_avx2(VoxelGrid::Words& words, int side);

}  // namespace esf::detail
