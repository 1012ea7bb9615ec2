// The AVX-512 kernels of the per-point passes (see esf_points.hpp).

#include <immintrin.h>

#include "core/simd.hpp"
#include "descriptors/esf/esf_point_kernels.hpp"

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Vectors passed between this file's internal functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace esf::detail {
namespace {

/// x, y and z of 16 consecutive points (48 floats).
ESF_TARGET_AVX512 inline void load16(const float* p, __m512& x, __m512& y, __m512& z) {
    const __m512 a = _mm512_loadu_ps(p), b = _mm512_loadu_ps(p + 16), c = _mm512_loadu_ps(p + 32);
    __m512* out[3] = {&x, &y, &z};
    for (int k = 0; k < 3; ++k) {
        alignas(64) int first[kLanes], second[kLanes];
        for (int l = 0; l < kLanes; ++l) {
            const int at = 3 * l + k;
            first[l] = at < 32 ? at : 0;
            second[l] = at < 32 ? l : 16 + at - 32;
        }
        const __m512 ab = _mm512_permutex2var_ps(a, _mm512_load_si512(first), b);
        *out[k] = _mm512_permutex2var_ps(ab, _mm512_load_si512(second), c);
    }
}

/// Lanes 0-7 (which = 0) or 8-15 of a vector.
ESF_TARGET_AVX512 inline __m256 half8(__m512 v, int which) {
    return which == 0 ? _mm512_castps512_ps256(v)
                      : _mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(v), 1));
}

/// The cell of 16 scaled coordinates, as cell_of().
ESF_TARGET_AVX512 inline __m512i cell16(__m512 v, int half) {
    const __m512i truncated = _mm512_cvttps_epi32(v);
    const __mmask16 fractional = _mm512_cmp_ps_mask(_mm512_cvtepi32_ps(truncated), v, _CMP_NEQ_UQ);
    const __mmask16 negative = _mm512_cmp_ps_mask(v, _mm512_setzero_ps(), _CMP_LT_OQ);
    const __m512i one = _mm512_set1_epi32(1);
    // v < 0: truncated - fractional + half; else truncated + fractional + half - 1.
    __m512i c = _mm512_add_epi32(truncated, _mm512_set1_epi32(half));
    c = _mm512_mask_sub_epi32(c, negative & fractional, c, one);
    c = _mm512_mask_sub_epi32(c, static_cast<__mmask16>(~negative & ~fractional), c, one);
    return _mm512_min_epi32(_mm512_max_epi32(c, _mm512_setzero_si512()),
                            _mm512_set1_epi32(2 * half - 1));
}

ESF_TARGET_AVX512 inline __m512 scale16(__m512 v, __m512d centre, __m512d scale) {
    const __m256 lo =
        _mm512_cvtpd_ps(_mm512_mul_pd(_mm512_sub_pd(_mm512_cvtps_pd(half8(v, 0)), centre), scale));
    const __m256 hi =
        _mm512_cvtpd_ps(_mm512_mul_pd(_mm512_sub_pd(_mm512_cvtps_pd(half8(v, 1)), centre), scale));
    return _mm512_insertf32x8(_mm512_castps256_ps512(lo), hi, 1);
}

}  // namespace

/// Sums of the first `blocks` x 16 points (AVX-512).
ESF_TARGET_AVX512 void sum_avx512(const float* p, std::size_t blocks, LaneSums& sums) {
    __m512d acc[3][2];
    for (int k = 0; k < 3; ++k)
        for (int h = 0; h < 2; ++h) acc[k][h] = _mm512_loadu_pd(sums.v[k] + 8 * h);
    for (std::size_t b = 0; b < blocks; ++b) {
        __m512 v[3];
        load16(p + 48 * b, v[0], v[1], v[2]);
        for (int k = 0; k < 3; ++k) {
            for (int h = 0; h < 2; ++h)
                acc[k][h] = _mm512_add_pd(acc[k][h], _mm512_cvtps_pd(half8(v[k], h)));
        }
    }
    for (int k = 0; k < 3; ++k)
        for (int h = 0; h < 2; ++h) _mm512_storeu_pd(sums.v[k] + 8 * h, acc[k][h]);
}

/// Largest squared distance from the centre of the first `blocks` x 16 points (AVX-512).
ESF_TARGET_AVX512 double radius2_avx512(const float* p, std::size_t blocks,
                                        const Normalisation& t) {
    const __m512d c[3] = {_mm512_set1_pd(t.cx), _mm512_set1_pd(t.cy), _mm512_set1_pd(t.cz)};
    __m512d largest = _mm512_setzero_pd();
    for (std::size_t b = 0; b < blocks; ++b) {
        __m512 v[3];
        load16(p + 48 * b, v[0], v[1], v[2]);
        for (int h = 0; h < 2; ++h) {
            __m512d r = _mm512_setzero_pd();
            for (int k = 0; k < 3; ++k) {
                const __m512d d = _mm512_sub_pd(_mm512_cvtps_pd(half8(v[k], h)), c[k]);
                r = k == 0 ? _mm512_mul_pd(d, d) : _mm512_add_pd(r, _mm512_mul_pd(d, d));
            }
            largest = _mm512_max_pd(largest, r);
        }
    }
    return _mm512_reduce_max_pd(largest);
}

ESF_TARGET_AVX512 std::size_t voxelise_avx512(const float* p, std::size_t blocks,
                                              const Normalisation& t, int half, PackedPoint* packed,
                                              std::uint32_t* cells, FloatMoments& moments) {
    std::size_t kept = 0;
    __m512i previous = _mm512_set1_epi32(-1);  // no cell: the first point always counts
    __m512 sums[9];
    for (int m = 0; m < 9; ++m) sums[m] = _mm512_load_ps(moments.v[m]);
    const __m512d centre[3] = {_mm512_set1_pd(t.cx), _mm512_set1_pd(t.cy), _mm512_set1_pd(t.cz)};
    const __m512d scale = _mm512_set1_pd(t.scale);
    for (std::size_t b = 0; b < blocks; ++b) {
        __m512 v[3];
        load16(p + 48 * b, v[0], v[1], v[2]);
        for (int k = 0; k < 3; ++k) v[k] = scale16(v[k], centre[k], scale);
        const __m512i cell = _mm512_or_si512(
            _mm512_or_si512(cell16(v[0], half), _mm512_slli_epi32(cell16(v[1], half), 6)),
            _mm512_slli_epi32(cell16(v[2], half), 12));
        // Lane l's predecessor: lane l - 1, or the previous block's last lane.
        const __mmask16 differs =
            _mm512_cmpneq_epi32_mask(cell, _mm512_alignr_epi32(cell, previous, 15));
        previous = cell;
        _mm512_storeu_si512(cells + kept, _mm512_maskz_compress_epi32(differs, cell));
        kept += static_cast<std::size_t>(std::popcount(static_cast<unsigned>(differs)));
        // Back to x, y, z, cell per point: 4x4 transposes within the 128-bit lanes.
        const __m512 w = _mm512_castsi512_ps(cell);
        const __m512 xy_lo = _mm512_unpacklo_ps(v[0], v[1]), xy_hi = _mm512_unpackhi_ps(v[0], v[1]);
        const __m512 zw_lo = _mm512_unpacklo_ps(v[2], w), zw_hi = _mm512_unpackhi_ps(v[2], w);
        const __m512 r[4] = {
            _mm512_castpd_ps(_mm512_unpacklo_pd(_mm512_castps_pd(xy_lo), _mm512_castps_pd(zw_lo))),
            _mm512_castpd_ps(_mm512_unpackhi_pd(_mm512_castps_pd(xy_lo), _mm512_castps_pd(zw_lo))),
            _mm512_castpd_ps(_mm512_unpacklo_pd(_mm512_castps_pd(xy_hi), _mm512_castps_pd(zw_hi))),
            _mm512_castpd_ps(_mm512_unpackhi_pd(_mm512_castps_pd(xy_hi), _mm512_castps_pd(zw_hi)))};
        // r[j] holds points 4q + j in its 128-bit lane q.
        float* out = &packed[kLanes * b].x;
        for (int j = 0; j < 4; ++j) {
            _mm_store_ps(out + 4 * j, _mm512_castps512_ps128(r[j]));
            _mm_store_ps(out + 4 * (4 + j), _mm512_extractf32x4_ps(r[j], 1));
            _mm_store_ps(out + 4 * (8 + j), _mm512_extractf32x4_ps(r[j], 2));
            _mm_store_ps(out + 4 * (12 + j), _mm512_extractf32x4_ps(r[j], 3));
        }
        for (int k = 0; k < 3; ++k) sums[k] = _mm512_add_ps(sums[k], v[k]);
        int m = 3;
        for (int k = 0; k < 3; ++k)
            for (int j = k; j < 3; ++j, ++m) sums[m] = _mm512_fmadd_ps(v[k], v[j], sums[m]);
    }
    for (int m = 0; m < 9; ++m) _mm512_store_ps(moments.v[m], sums[m]);
    return kept;
}

}  // namespace esf::detail
