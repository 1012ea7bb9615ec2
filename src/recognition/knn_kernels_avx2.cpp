// The AVX2 distance kernels of the k-NN index (see knn_kernels.hpp).

#include <immintrin.h>

#include "core/simd.hpp"
#include "recognition/knn_kernels.hpp"

// GCC 12's AVX-512 headers start from _mm512_undefined_*() values and trip
// -Wmaybe-uninitialized once inlined (GCC bug 105593); the values are fully written.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace esf::detail {

namespace {

/// Exact conversion of 64-bit integers below 2^52 to double: (2^52 + x) - 2^52.
ESF_TARGET_AVX2 inline __m256d u52_to_double(__m256i x) {
    const __m256d magic = _mm256_set1_pd(4503599627370496.0);
    return _mm256_sub_pd(_mm256_castsi256_pd(_mm256_or_si256(x, _mm256_castpd_si256(magic))),
                         magic);
}

/// Four 64-bit partial sums per row: lane weights times SADs, over the whole row.
ESF_TARGET_AVX2 inline __m256i weighted_sad_avx2(const std::uint8_t* row, const std::uint8_t* query,
                                                 const std::uint32_t* weight, std::size_t stride) {
    __m256i acc = _mm256_setzero_si256();
    std::size_t c = 0;
    for (; c + 32 <= stride; c += 32) {
        const __m256i sad =
            _mm256_sad_epu8(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + c)),
                            _mm256_loadu_si256(reinterpret_cast<const __m256i*>(query + c)));
        const __m256i w = _mm256_cvtepu32_epi64(
            _mm_loadu_si128(reinterpret_cast<const __m128i*>(weight + c / 8)));
        acc = _mm256_add_epi64(acc, _mm256_mul_epu32(sad, w));
    }
    if (c < stride) {  // 16 bytes left: two lanes (the weights are padded with zeros)
        const __m256i sad = _mm256_sad_epu8(
            _mm256_set_m128i(_mm_setzero_si128(),
                             _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + c))),
            _mm256_set_m128i(_mm_setzero_si128(),
                             _mm_loadu_si128(reinterpret_cast<const __m128i*>(query + c))));
        const __m256i w = _mm256_cvtepu32_epi64(
            _mm_loadu_si128(reinterpret_cast<const __m128i*>(weight + c / 8)));
        acc = _mm256_add_epi64(acc, _mm256_mul_epu32(sad, w));
    }
    return acc;
}

ESF_TARGET_AVX2 inline __m256i load256(const std::uint8_t* at) {
    return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(at));
}

/// Transposed sums of four rows' lane sums ([a0+a1 b0+b1 | a2+a3 b2+b3], then across the
/// halves: [a b c d]), turned into bounds and kept where they do not exceed the limit.
ESF_TARGET_AVX2 inline std::size_t keep_bounds4(const __m256i* p, __m256d scale,
                                                const double* row_error, __m256d query_error,
                                                __m256d limit, std::uint32_t first_row,
                                                std::size_t kept, double* bound,
                                                std::uint32_t* row) {
    const __m256i t01 =
        _mm256_add_epi64(_mm256_unpacklo_epi64(p[0], p[1]), _mm256_unpackhi_epi64(p[0], p[1]));
    const __m256i t23 =
        _mm256_add_epi64(_mm256_unpacklo_epi64(p[2], p[3]), _mm256_unpackhi_epi64(p[2], p[3]));
    const __m256i total = _mm256_add_epi64(_mm256_permute2x128_si256(t01, t23, 0x20),
                                           _mm256_permute2x128_si256(t01, t23, 0x31));
    const __m256d estimate = _mm256_mul_pd(u52_to_double(total), scale);
    const __m256d bounds =
        _mm256_sub_pd(_mm256_sub_pd(estimate, _mm256_loadu_pd(row_error)), query_error);
    const auto below =
        static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(bounds, limit, _CMP_LE_OQ)));
    if (below == 0) return kept;
    alignas(32) double values[4];
    _mm256_store_pd(values, bounds);
    return keep_rows(values, below, first_row, kept, bound, row);
}

}  // namespace

ESF_TARGET_AVX2 double exact_avx2(const float* a, const float* b, const float* w, std::size_t n,
                                  double limit) {
    const __m256d sign = _mm256_set1_pd(-0.0);
    __m256d lo = _mm256_setzero_pd();  // lanes 0..3
    __m256d hi = _mm256_setzero_pd();  // lanes 4..7
    alignas(32) double lane[8];
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        if (i != 0 && i % kExactCheck == 0) {
            _mm256_store_pd(lane, lo);
            _mm256_store_pd(lane + 4, hi);
            if (const double partial = combine_lanes(lane); partial > limit) return partial;
        }
        const __m256d a_lo = _mm256_cvtps_pd(_mm_loadu_ps(a + i));
        const __m256d a_hi = _mm256_cvtps_pd(_mm_loadu_ps(a + i + 4));
        const __m256d b_lo = _mm256_cvtps_pd(_mm_loadu_ps(b + i));
        const __m256d b_hi = _mm256_cvtps_pd(_mm_loadu_ps(b + i + 4));
        const __m256d w_lo = _mm256_cvtps_pd(_mm_loadu_ps(w + i));
        const __m256d w_hi = _mm256_cvtps_pd(_mm_loadu_ps(w + i + 4));
        const __m256d d_lo = _mm256_andnot_pd(sign, _mm256_sub_pd(a_lo, b_lo));
        const __m256d d_hi = _mm256_andnot_pd(sign, _mm256_sub_pd(a_hi, b_hi));
        lo = _mm256_add_pd(lo, _mm256_mul_pd(w_lo, d_lo));
        hi = _mm256_add_pd(hi, _mm256_mul_pd(w_hi, d_hi));
    }
    _mm256_store_pd(lane, lo);
    _mm256_store_pd(lane + 4, hi);
    exact_tail(a, b, w, i, n, lane);
    return combine_lanes(lane);
}

ESF_TARGET_AVX2 std::size_t sketch_avx2(const std::uint8_t* rows, std::size_t count,
                                        std::size_t stride, const std::uint8_t* query,
                                        const std::uint32_t* weight, double unit,
                                        const double* row_error, double query_error, double limit,
                                        std::uint32_t first_row, double* bound,
                                        std::uint32_t* row) {
    const __m256d scale = _mm256_set1_pd(unit);
    const __m256d error = _mm256_set1_pd(query_error);
    const __m256d limits = _mm256_set1_pd(limit);
    std::size_t r = 0;
    std::size_t kept = 0;
    __m256i p[4];
    if (stride == 64) {  // two SADs per row: every default sketch up to 4096 dimensions
        const __m256i q0 = load256(query), q1 = load256(query + 32);
        const __m256i w0 =
            _mm256_cvtepu32_epi64(_mm_loadu_si128(reinterpret_cast<const __m128i*>(weight)));
        const __m256i w1 =
            _mm256_cvtepu32_epi64(_mm_loadu_si128(reinterpret_cast<const __m128i*>(weight + 4)));
        for (; r + 4 <= count; r += 4) {
            for (std::size_t i = 0; i < 4; ++i) {
                const std::uint8_t* codes = rows + (r + i) * 64;
                p[i] = _mm256_add_epi64(
                    _mm256_mul_epu32(_mm256_sad_epu8(load256(codes), q0), w0),
                    _mm256_mul_epu32(_mm256_sad_epu8(load256(codes + 32), q1), w1));
            }
            kept = keep_bounds4(p, scale, row_error + r, error, limits,
                                first_row + static_cast<std::uint32_t>(r), kept, bound, row);
        }
    }
    for (; r + 4 <= count; r += 4) {
        for (std::size_t i = 0; i < 4; ++i)
            p[i] = weighted_sad_avx2(rows + (r + i) * stride, query, weight, stride);
        kept = keep_bounds4(p, scale, row_error + r, error, limits,
                            first_row + static_cast<std::uint32_t>(r), kept, bound, row);
    }
    for (; r < count; ++r) {
        alignas(32) std::uint64_t part[4];
        _mm256_store_si256(reinterpret_cast<__m256i*>(part),
                           weighted_sad_avx2(rows + r * stride, query, weight, stride));
        const double estimate =
            unit * static_cast<double>((part[0] + part[1]) + (part[2] + part[3]));
        const double row_bound = (estimate - row_error[r]) - query_error;
        if (row_bound <= limit)
            kept = keep_rows(&row_bound, 1u, first_row + static_cast<std::uint32_t>(r), kept, bound,
                             row);
    }
    return kept;
}

}  // namespace esf::detail
