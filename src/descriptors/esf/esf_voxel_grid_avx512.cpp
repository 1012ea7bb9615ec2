// The AVX-512 kernel of the voxel grid's dilation (see esf_voxel_grid.hpp).

#include <immintrin.h>

#include "core/simd.hpp"
#include "descriptors/esf/esf_voxel_grid.hpp"

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Vectors passed between this file's internal functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace esf::detail {

/// dilate_portable() on 8 words per step.
ESF_TARGET_AVX512 void dilate_avx512(VoxelGrid::Words& words, int side) {
    const __m512i x_mask =
        _mm512_set1_epi64(side >= 64 ? -1 : static_cast<long long>((std::uint64_t{1} << side) - 1));
    const __m512i lane_y = _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7);
    // Along x, in place.
    for (int r = 0; r < kGridWords; r += 8) {
        const __m512i w = _mm512_load_si512(&words[static_cast<std::size_t>(r)]);
        _mm512_store_si512(
            &words[static_cast<std::size_t>(r)],
            _mm512_and_si512(_mm512_or_si512(w, _mm512_or_si512(_mm512_slli_epi64(w, 1),
                                                                _mm512_srli_epi64(w, 1))),
                             x_mask));
    }
    // Along y, into `rows` (one zero row before and after each slice's neighbours).
    alignas(64) VoxelGrid::Words rows;
    const __m512i below_side = _mm512_set1_epi64(side);
    for (int z = 0; z < kGridSide; ++z) {
        const std::uint64_t* slice = &words[static_cast<std::size_t>(z * kGridSide)];
        for (int y = 0; y < kGridSide; y += 8) {
            const __m512i ys = _mm512_add_epi64(lane_y, _mm512_set1_epi64(y));
            const __mmask8 has_prev = _mm512_cmpgt_epi64_mask(ys, _mm512_setzero_si512());
            const __mmask8 has_next =
                _mm512_cmplt_epi64_mask(_mm512_add_epi64(ys, _mm512_set1_epi64(1)), below_side);
            const __mmask8 inside = _mm512_cmplt_epi64_mask(ys, below_side);
            const __m512i prev = _mm512_maskz_loadu_epi64(has_prev, slice + y - 1);
            const __m512i next = _mm512_maskz_loadu_epi64(has_next, slice + y + 1);
            const __m512i w = _mm512_load_si512(slice + y);
            _mm512_store_si512(
                &rows[static_cast<std::size_t>(z * kGridSide + y)],
                _mm512_maskz_mov_epi64(inside, _mm512_or_si512(w, _mm512_or_si512(prev, next))));
        }
    }
    dilate_along_z(rows, words, side);
}

}  // namespace esf::detail
