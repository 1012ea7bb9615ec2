// The AVX-512 distance kernels of the k-NN index (see knn_kernels.hpp).

#include <immintrin.h>

#include "core/simd.hpp"
#include "recognition/knn_kernels.hpp"

// GCC 12's AVX-512 headers start from _mm512_undefined_*() values and trip
// -Wmaybe-uninitialized once inlined (GCC bug 105593); the values are fully written.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace esf::detail {

namespace {

/// Exact conversion of 64-bit integers below 2^52 to double: (2^52 + x) - 2^52.
ESF_TARGET_AVX512 inline __m512d u52_to_double(__m512i x) {
    const __m512d magic = _mm512_set1_pd(4503599627370496.0);
    return _mm512_sub_pd(_mm512_castsi512_pd(_mm512_or_si512(x, _mm512_castpd_si512(magic))),
                         magic);
}

/// Eight 64-bit partial sums per row: lane weights times SADs, over the whole row.
ESF_TARGET_AVX512 inline __m512i weighted_sad_avx512(const std::uint8_t* row,
                                                     const std::uint8_t* query,
                                                     const std::uint32_t* weight,
                                                     std::size_t stride) {
    __m512i acc = _mm512_setzero_si512();
    std::size_t c = 0;
    for (; c + 64 <= stride; c += 64) {
        const __m512i sad =
            _mm512_sad_epu8(_mm512_loadu_si512(row + c), _mm512_loadu_si512(query + c));
        const __m512i w = _mm512_cvtepu32_epi64(
            _mm256_loadu_si256(reinterpret_cast<const __m256i*>(weight + c / 8)));
        acc = _mm512_add_epi64(acc, _mm512_mul_epu32(sad, w));
    }
    if (c < stride) {  // 16, 32 or 48 bytes left (the weights are padded with zeros)
        const __mmask64 mask = (std::uint64_t{1} << (stride - c)) - 1;
        const __m512i sad = _mm512_sad_epu8(_mm512_maskz_loadu_epi8(mask, row + c),
                                            _mm512_maskz_loadu_epi8(mask, query + c));
        const __m512i w = _mm512_cvtepu32_epi64(
            _mm256_loadu_si256(reinterpret_cast<const __m256i*>(weight + c / 8)));
        acc = _mm512_add_epi64(acc, _mm512_mul_epu32(sad, w));
    }
    return acc;
}

/// Pairwise sums of the 64-bit lanes of a and b: [a0+a1 b0+b1 | a2+a3 b2+b3 | ...].
ESF_TARGET_AVX512 inline __m512i pair_sums(__m512i a, __m512i b) {
    return _mm512_add_epi64(_mm512_unpacklo_epi64(a, b), _mm512_unpackhi_epi64(a, b));
}

/// Sums of 128-bit blocks: [a.0+a.1 | a.2+a.3 | b.0+b.1 | b.2+b.3].
ESF_TARGET_AVX512 inline __m512i block_sums(__m512i a, __m512i b) {
    return _mm512_add_epi64(_mm512_shuffle_i64x2(a, b, _MM_SHUFFLE(2, 0, 2, 0)),
                            _mm512_shuffle_i64x2(a, b, _MM_SHUFFLE(3, 1, 3, 1)));
}

/// Transposed sums of eight rows' lane sums (row i's total in lane i), turned into bounds and
/// kept where they do not exceed the limit.
ESF_TARGET_AVX512 inline std::size_t keep_bounds8(const __m512i* p, __m512d scale,
                                                  const double* row_error, __m512d query_error,
                                                  __m512d limit, std::uint32_t first_row,
                                                  std::size_t kept, double* bound,
                                                  std::uint32_t* row) {
    const __m512i total = block_sums(block_sums(pair_sums(p[0], p[1]), pair_sums(p[2], p[3])),
                                     block_sums(pair_sums(p[4], p[5]), pair_sums(p[6], p[7])));
    const __m512d estimate = _mm512_mul_pd(u52_to_double(total), scale);
    const __m512d bounds =
        _mm512_sub_pd(_mm512_sub_pd(estimate, _mm512_loadu_pd(row_error)), query_error);
    const __mmask8 below = _mm512_cmp_pd_mask(bounds, limit, _CMP_LE_OQ);
    if (below == 0) return kept;
    alignas(64) double values[8];
    _mm512_store_pd(values, bounds);
    return keep_rows(values, below, first_row, kept, bound, row);
}

}  // namespace

ESF_TARGET_AVX512 double exact_avx512(const float* a, const float* b, const float* w, std::size_t n,
                                      double limit) {
    __m512d acc = _mm512_setzero_pd();  // lanes 0..7
    alignas(64) double lane[8];
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        if (i != 0 && i % kExactCheck == 0) {
            _mm512_store_pd(lane, acc);
            if (const double partial = combine_lanes(lane); partial > limit) return partial;
        }
        const __m512d av = _mm512_cvtps_pd(_mm256_loadu_ps(a + i));
        const __m512d bv = _mm512_cvtps_pd(_mm256_loadu_ps(b + i));
        const __m512d wv = _mm512_cvtps_pd(_mm256_loadu_ps(w + i));
        acc = _mm512_add_pd(acc, _mm512_mul_pd(wv, _mm512_abs_pd(_mm512_sub_pd(av, bv))));
    }
    _mm512_store_pd(lane, acc);
    exact_tail(a, b, w, i, n, lane);
    return combine_lanes(lane);
}

ESF_TARGET_AVX512 std::size_t sketch_avx512(const std::uint8_t* rows, std::size_t count,
                                            std::size_t stride, const std::uint8_t* query,
                                            const std::uint32_t* weight, double unit,
                                            const double* row_error, double query_error,
                                            double limit, std::uint32_t first_row, double* bound,
                                            std::uint32_t* row) {
    const __m512d scale = _mm512_set1_pd(unit);
    const __m512d error = _mm512_set1_pd(query_error);
    const __m512d limits = _mm512_set1_pd(limit);
    std::size_t r = 0;
    std::size_t kept = 0;
    __m512i p[8];
    if (stride == 64) {  // one SAD per row: every default sketch up to 4096 dimensions
        const __m512i q = _mm512_loadu_si512(query);
        const __m512i w =
            _mm512_cvtepu32_epi64(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(weight)));
        for (; r + 8 <= count; r += 8) {
            for (std::size_t i = 0; i < 8; ++i)
                p[i] = _mm512_mul_epu32(_mm512_sad_epu8(_mm512_loadu_si512(rows + (r + i) * 64), q),
                                        w);
            kept = keep_bounds8(p, scale, row_error + r, error, limits,
                                first_row + static_cast<std::uint32_t>(r), kept, bound, row);
        }
    }
    for (; r + 8 <= count; r += 8) {
        for (std::size_t i = 0; i < 8; ++i)
            p[i] = weighted_sad_avx512(rows + (r + i) * stride, query, weight, stride);
        kept = keep_bounds8(p, scale, row_error + r, error, limits,
                            first_row + static_cast<std::uint32_t>(r), kept, bound, row);
    }
    for (; r < count; ++r) {
        const __m512i part = weighted_sad_avx512(rows + r * stride, query, weight, stride);
        const double estimate =
            unit * static_cast<double>(static_cast<std::uint64_t>(_mm512_reduce_add_epi64(part)));
        const double row_bound = (estimate - row_error[r]) - query_error;
        if (row_bound <= limit)
            kept = keep_rows(&row_bound, 1u, first_row + static_cast<std::uint32_t>(r), kept, bound,
                             row);
    }
    return kept;
}

}  // namespace esf::detail
