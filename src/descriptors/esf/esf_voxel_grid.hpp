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

/// VoxelGrid::dilate() on `words`, the one copy of every kernel: the 3x3x3 box is separable,
/// so the bits are dilated along x, then the rows along y, then the slices along z. Inline, so
/// that each kernel's build vectorises it for its own instruction set.
[[gnu::always_inline]] inline void dilate_words(VoxelGrid::Words& words, int side) {
    const std::uint64_t x_mask = side >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << side) - 1;
    for (auto& word : words) word = (word | (word << 1) | (word >> 1)) & x_mask;
    // Along y, into `rows`: a slice's rows y - 1 and y + 1 where they lie in the first `side`.
    alignas(64) VoxelGrid::Words rows;
    for (int z = 0; z < kGridSide; ++z) {
        const std::uint64_t* slice = &words[static_cast<std::size_t>(z * kGridSide)];
        std::uint64_t* out = &rows[static_cast<std::size_t>(z * kGridSide)];
        out[0] = side > 1 ? slice[0] | slice[1] : slice[0];
        for (int y = 1; y + 1 < side; ++y) out[y] = slice[y - 1] | slice[y] | slice[y + 1];
        if (side > 1) out[side - 1] = slice[side - 2] | slice[side - 1];
        for (int y = side; y < kGridSide; ++y) out[y] = 0;
    }
    // Along z, back into the grid.
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
