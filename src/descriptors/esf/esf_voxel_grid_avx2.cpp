// The AVX2 kernel of the voxel grid's dilation (see esf_voxel_grid.hpp).

#include <immintrin.h>

#include "core/simd.hpp"
#include "descriptors/esf/esf_voxel_grid.hpp"

// Vectors passed between this file's internal lambdas (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace esf::detail {

/// dilate_portable() on 4 words per step.
ESF_TARGET_AVX2 void dilate_avx2(VoxelGrid::Words& words, int side) {
    const __m256i x_mask = _mm256_set1_epi64x(
        side >= 64 ? -1 : static_cast<long long>((std::uint64_t{1} << side) - 1));
    const auto load = [](const std::uint64_t* at) ESF_TARGET_AVX2 {
        return _mm256_load_si256(reinterpret_cast<const __m256i*>(at));
    };
    const auto store = [](std::uint64_t* at, __m256i v) ESF_TARGET_AVX2 {
        _mm256_store_si256(reinterpret_cast<__m256i*>(at), v);
    };
    // Along x, in place.
    for (int r = 0; r < kGridWords; r += 4) {
        const __m256i w = load(&words[static_cast<std::size_t>(r)]);
        store(&words[static_cast<std::size_t>(r)],
              _mm256_and_si256(_mm256_or_si256(w, _mm256_or_si256(_mm256_slli_epi64(w, 1),
                                                                  _mm256_srli_epi64(w, 1))),
                               x_mask));
    }
    // Along y, into `rows`: a slice's rows y - 1 and y + 1 where they lie in the first `side`.
    alignas(64) VoxelGrid::Words rows;
    const __m256i lane_y = _mm256_setr_epi64x(0, 1, 2, 3);
    const __m256i below_side = _mm256_set1_epi64x(side);
    for (int z = 0; z < kGridSide; ++z) {
        const std::uint64_t* slice = &words[static_cast<std::size_t>(z * kGridSide)];
        for (int y = 0; y < kGridSide; y += 4) {
            const __m256i ys = _mm256_add_epi64(lane_y, _mm256_set1_epi64x(y));
            const __m256i has_prev = _mm256_cmpgt_epi64(ys, _mm256_setzero_si256());
            const __m256i has_next =
                _mm256_cmpgt_epi64(below_side, _mm256_add_epi64(ys, _mm256_set1_epi64x(1)));
            const __m256i inside = _mm256_cmpgt_epi64(below_side, ys);
            // Masked loads never touch the words outside the slice that they leave out.
            const __m256i prev =
                _mm256_maskload_epi64(reinterpret_cast<const long long*>(slice + y - 1), has_prev);
            const __m256i next =
                _mm256_maskload_epi64(reinterpret_cast<const long long*>(slice + y + 1), has_next);
            const __m256i w = load(slice + y);
            store(&rows[static_cast<std::size_t>(z * kGridSide + y)],
                  _mm256_and_si256(inside, _mm256_or_si256(w, _mm256_or_si256(prev, next))));
        }
    }
    dilate_along_z(rows, words, side);
}

}  // namespace esf::detail
