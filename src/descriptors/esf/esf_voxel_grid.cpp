#include "descriptors/esf/esf_voxel_grid.hpp"

#include <algorithm>

#include "core/simd.hpp"

namespace esf::detail {

void VoxelGrid::dilate(int side, SimdLevel simd) {
    const SimdLevel level = std::min(simd, best_simd_level());
    if (level == SimdLevel::kAvx512)
        dilate_avx512(words, side);
    else if (level == SimdLevel::kAvx2)
        dilate_avx2(words, side);
    else
        dilate_words(words, side);
}

}  // namespace esf::detail
