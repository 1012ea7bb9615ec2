// The AVX-512 build of the voxel grid's dilation (see esf_voxel_grid.hpp).

#include "core/simd.hpp"
#include "descriptors/esf/esf_voxel_grid.hpp"

namespace esf::detail {

ESF_TARGET_AVX512 void dilate_avx512(VoxelGrid::Words& words, int side) {
    dilate_words(words, side);
}

}  // namespace esf::detail
