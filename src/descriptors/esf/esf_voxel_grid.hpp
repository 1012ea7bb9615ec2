#pragma once
// Internal: the voxel grid of the ESF descriptor (Sec. III-B), a 64^3 bit array (32 KiB, cache
// resident): cell (x, y, z) is bit x | y << 6 | z << 12.

#include <array>
#include <cstddef>
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

/// The last step of VoxelGrid::dilate(), shared by every kernel: row (y, z) of `words` becomes
/// the rows (y, z - 1), (y, z) and (y, z + 1) of `rows` together, the slices z < `side` only.
/// Inline, so that each kernel's build vectorises it for its own instruction set.
inline void dilate_along_z(const VoxelGrid::Words& rows, VoxelGrid::Words& words, int side) {
    for (int z = 0; z < kGridSide; ++z) {
        const bool has_prev = z > 0, has_next = z + 1 < side, inside = z < side;
        const std::size_t slice = static_cast<std::size_t>(z * kGridSide);
        for (std::size_t r = slice; r < slice + kGridSide; ++r) {
            std::uint64_t word = 0;
            if (inside) {
                word = rows[r];
                if (has_prev) word |= rows[r - kGridSide];
                if (has_next) word |= rows[r + kGridSide];
            }
            words[r] = word;
        }
    }
}

/// VoxelGrid::dilate() with AVX-512 (the same bits); needs avx512_available().
void dilate_avx512(VoxelGrid::Words& words, int side);
/// VoxelGrid::dilate() with AVX2 (the same bits); needs avx2_available().
void dilate_avx2(VoxelGrid::Words& words, int side);

}  // namespace esf::detail
