#include "descriptors/esf/esf_voxel_grid.hpp"

#include <algorithm>

#include "core/simd.hpp"

namespace esf::detail {

namespace {

void dilate_portable(VoxelGrid::Words& words, int side) {
    // The 3x3x3 box is separable: dilate along x (bits), then y (rows), then z (slices).
    const std::uint64_t x_mask = side >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << side) - 1;
    for (auto& word : words) word = (word | (word << 1) | (word >> 1)) & x_mask;
    VoxelGrid::Words rows{};  // slices' rows y - 1, y, y + 1 together, for y < side
    for (int z = 0; z < side; ++z) {
        for (int y = 0; y < side; ++y) {
            const int row = (z << kGridBits) | y;
            std::uint64_t word = words[static_cast<std::size_t>(row)];
            if (y > 0) word |= words[static_cast<std::size_t>(row - 1)];
            if (y + 1 < side) word |= words[static_cast<std::size_t>(row + 1)];
            rows[static_cast<std::size_t>(row)] = word;
        }
    }
    dilate_along_z(rows, words, side);
}

}  // namespace

void VoxelGrid::dilate(int side, SimdLevel simd) {
    const SimdLevel level = std::min(simd, best_simd_level());
    if (level == SimdLevel::kAvx512)
        dilate_avx512(words, side);
    else if (level == SimdLevel::kAvx2)
        dilate_avx2(words, side);
    else
        dilate_portable(words, side);
}

}  // namespace esf::detail
