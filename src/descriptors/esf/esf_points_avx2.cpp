// The AVX2 kernels of the per-point passes (see esf_points.hpp): 16 points as two halves of 8,
// each coordinate as four vectors of 4 doubles.

#include <immintrin.h>

#include "core/simd.hpp"
#include "descriptors/esf/esf_point_kernels.hpp"

// Vectors passed between this file's internal functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace esf::detail {
namespace {

/// Lanes of the blend of three vectors of 8 floats that hold coordinate K of 8 points.
template <int K>
constexpr int blend_from(int source) {
    int mask = 0;
    for (int j = 0; j < 8; ++j)
        if ((2 * source + j) % 3 == K) mask |= 1 << j;
    return mask;
}

/// Coordinate K of the 8 points in a, b, c (24 floats).
template <int K>
ESF_TARGET_AVX2 inline __m256 coordinate8(__m256 a, __m256 b, __m256 c) {
    const __m256 m = _mm256_blend_ps(_mm256_blend_ps(a, b, blend_from<K>(1)), c, blend_from<K>(2));
    return _mm256_permutevar8x32_ps(
        m, _mm256_setr_epi32(K % 8, (3 + K) % 8, (6 + K) % 8, (9 + K) % 8, (12 + K) % 8,
                             (15 + K) % 8, (18 + K) % 8, (21 + K) % 8));
}

/// x, y and z of 8 consecutive points (24 floats).
ESF_TARGET_AVX2 inline void load8(const float* p, __m256& x, __m256& y, __m256& z) {
    const __m256 a = _mm256_loadu_ps(p), b = _mm256_loadu_ps(p + 8), c = _mm256_loadu_ps(p + 16);
    x = coordinate8<0>(a, b, c);
    y = coordinate8<1>(a, b, c);
    z = coordinate8<2>(a, b, c);
}

/// Lanes 0-3 (which = 0) or 4-7 of a vector, in double.
ESF_TARGET_AVX2 inline __m256d quarter4(__m256 v, int which) {
    return _mm256_cvtps_pd(which == 0 ? _mm256_castps256_ps128(v) : _mm256_extractf128_ps(v, 1));
}

/// The cell of 8 scaled coordinates, as cell_of().
ESF_TARGET_AVX2 inline __m256i cell8(__m256 v, int half) {
    const __m256i truncated = _mm256_cvttps_epi32(v);
    const __m256i fractional =
        _mm256_castps_si256(_mm256_cmp_ps(_mm256_cvtepi32_ps(truncated), v, _CMP_NEQ_UQ));
    const __m256i negative = _mm256_castps_si256(_mm256_cmp_ps(v, _mm256_setzero_ps(), _CMP_LT_OQ));
    // v < 0: truncated - fractional + half; else truncated + fractional + half - 1 (the masks
    // are -1 where set).
    __m256i c = _mm256_add_epi32(truncated, _mm256_set1_epi32(half));
    c = _mm256_add_epi32(c, _mm256_and_si256(negative, fractional));
    c = _mm256_add_epi32(
        c, _mm256_andnot_si256(_mm256_or_si256(negative, fractional), _mm256_set1_epi32(-1)));
    return _mm256_min_epi32(_mm256_max_epi32(c, _mm256_setzero_si256()),
                            _mm256_set1_epi32(2 * half - 1));
}

ESF_TARGET_AVX2 inline __m256 scale8(__m256 v, __m256d centre, __m256d scale) {
    const __m128 lo = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(quarter4(v, 0), centre), scale));
    const __m128 hi = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(quarter4(v, 1), centre), scale));
    return _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
}

}  // namespace

/// Sums of the first `blocks` x 16 points (AVX2).
ESF_TARGET_AVX2 void sum_avx2(const float* p, std::size_t blocks, LaneSums& sums) {
    __m256d acc[3][4];
    for (int k = 0; k < 3; ++k)
        for (int q = 0; q < 4; ++q) acc[k][q] = _mm256_loadu_pd(sums.v[k] + 4 * q);
    for (std::size_t b = 0; b < blocks; ++b) {
        for (int h = 0; h < 2; ++h) {
            __m256 v[3];
            load8(p + 48 * b + 24 * h, v[0], v[1], v[2]);
            for (int k = 0; k < 3; ++k)
                for (int q = 0; q < 2; ++q)
                    acc[k][2 * h + q] = _mm256_add_pd(acc[k][2 * h + q], quarter4(v[k], q));
        }
    }
    for (int k = 0; k < 3; ++k)
        for (int q = 0; q < 4; ++q) _mm256_storeu_pd(sums.v[k] + 4 * q, acc[k][q]);
}

/// Largest squared distance from the centre of the first `blocks` x 16 points (AVX2).
ESF_TARGET_AVX2 double radius2_avx2(const float* p, std::size_t blocks, const Normalisation& t) {
    const __m256d c[3] = {_mm256_set1_pd(t.cx), _mm256_set1_pd(t.cy), _mm256_set1_pd(t.cz)};
    __m256d largest = _mm256_setzero_pd();
    for (std::size_t i = 0; i < 2 * blocks; ++i) {
        __m256 v[3];
        load8(p + 24 * i, v[0], v[1], v[2]);
        for (int q = 0; q < 2; ++q) {
            __m256d r = _mm256_setzero_pd();
            for (int k = 0; k < 3; ++k) {
                const __m256d d = _mm256_sub_pd(quarter4(v[k], q), c[k]);
                r = k == 0 ? _mm256_mul_pd(d, d) : _mm256_add_pd(r, _mm256_mul_pd(d, d));
            }
            largest = _mm256_max_pd(largest, r);
        }
    }
    alignas(32) double lanes[4];
    _mm256_store_pd(lanes, largest);
    return std::max(std::max(lanes[0], lanes[1]), std::max(lanes[2], lanes[3]));
}

ESF_TARGET_AVX2 void voxelise_avx2(const float* p, std::size_t blocks, const Normalisation& t,
                                   int half, PackedPoint* packed, std::uint32_t* cells,
                                   LaneMoments& moments) {
    const __m256d centre[3] = {_mm256_set1_pd(t.cx), _mm256_set1_pd(t.cy), _mm256_set1_pd(t.cz)};
    const __m256d scale = _mm256_set1_pd(t.scale);
    for (std::size_t i = 0; i < 2 * blocks; ++i) {
        __m256 v[3];
        load8(p + 24 * i, v[0], v[1], v[2]);
        for (int k = 0; k < 3; ++k) v[k] = scale8(v[k], centre[k], scale);
        const __m256i cell = _mm256_or_si256(
            _mm256_or_si256(cell8(v[0], half), _mm256_slli_epi32(cell8(v[1], half), 6)),
            _mm256_slli_epi32(cell8(v[2], half), 12));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(cells + 8 * i), cell);
        // Back to x, y, z, cell per point: 4x4 transposes within the 128-bit lanes.
        const __m256 w = _mm256_castsi256_ps(cell);
        const __m256 xy_lo = _mm256_unpacklo_ps(v[0], v[1]), xy_hi = _mm256_unpackhi_ps(v[0], v[1]);
        const __m256 zw_lo = _mm256_unpacklo_ps(v[2], w), zw_hi = _mm256_unpackhi_ps(v[2], w);
        const __m256 r[4] = {
            _mm256_castpd_ps(_mm256_unpacklo_pd(_mm256_castps_pd(xy_lo), _mm256_castps_pd(zw_lo))),
            _mm256_castpd_ps(_mm256_unpackhi_pd(_mm256_castps_pd(xy_lo), _mm256_castps_pd(zw_lo))),
            _mm256_castpd_ps(_mm256_unpacklo_pd(_mm256_castps_pd(xy_hi), _mm256_castps_pd(zw_hi))),
            _mm256_castpd_ps(_mm256_unpackhi_pd(_mm256_castps_pd(xy_hi), _mm256_castps_pd(zw_hi)))};
        // r[j] holds points 4q + j in its 128-bit lane q.
        float* out = &packed[8 * i].x;
        for (int j = 0; j < 4; ++j) {
            _mm_store_ps(out + 4 * j, _mm256_castps256_ps128(r[j]));
            _mm_store_ps(out + 4 * (4 + j), _mm256_extractf128_ps(r[j], 1));
        }
        // Points 8 i .. 8 i + 7 go to lanes 8 (i % 2) ...
        const std::size_t lane = 8 * (i % 2);
        for (int k = 0; k < 3; ++k)
            for (int q = 0; q < 2; ++q) {
                double* lanes = moments.v[k] + lane + 4 * q;
                _mm256_storeu_pd(lanes, _mm256_add_pd(_mm256_loadu_pd(lanes), quarter4(v[k], q)));
            }
        int m = 3;
        for (int k = 0; k < 3; ++k)
            for (int j = k; j < 3; ++j) {
                // Products in double, as the portable code forms them.
                double* lanes = moments.v[m++] + lane;
                for (int q = 0; q < 2; ++q) {
                    const __m256d a = quarter4(v[k], q), c = quarter4(v[j], q);
                    _mm256_storeu_pd(lanes + 4 * q, _mm256_add_pd(_mm256_loadu_pd(lanes + 4 * q),
                                                                  _mm256_mul_pd(a, c)));
                }
            }
    }
}

}  // namespace esf::detail
