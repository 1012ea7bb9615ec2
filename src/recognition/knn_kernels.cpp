#include "recognition/knn_kernels.hpp"

#if defined(__x86_64__) || defined(__i386__)
#define ESF_KNN_X86 1
#include <immintrin.h>
#else
#define ESF_KNN_X86 0
#endif

#include <cmath>
#include <cstdlib>

namespace esf {
namespace {

/// The fixed pairwise combination of the eight lanes shared by every exact kernel.
inline double combine_lanes(const double* lane) {
    return ((lane[0] + lane[4]) + (lane[2] + lane[6])) +
           ((lane[1] + lane[5]) + (lane[3] + lane[7]));
}

/// Adds the elements [begin, n) to their lanes (begin is a multiple of 8).
inline void exact_tail(const float* a, const float* b, const float* w, std::size_t begin,
                       std::size_t n, double* lane) {
    for (std::size_t i = begin; i < n; ++i)
        lane[i & 7] += static_cast<double>(w[i]) *
                       std::fabs(static_cast<double>(a[i]) - static_cast<double>(b[i]));
}

double exact_scalar(const float* a, const float* b, const float* w, std::size_t n, double limit) {
    double lane[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    std::size_t i = 0;
    for (; i + detail::kExactCheck < n; i += detail::kExactCheck) {
        exact_tail(a, b, w, i, i + detail::kExactCheck, lane);
        if (const double partial = combine_lanes(lane); partial > limit) return partial;
    }
    exact_tail(a, b, w, i, n, lane);
    return combine_lanes(lane);
}

void sketch_scalar(const std::uint8_t* rows, std::size_t count, std::size_t stride,
                   const std::uint8_t* query, const std::uint32_t* weight, double unit,
                   const double* row_error, double query_error, double* bound) {
    const std::size_t lanes = stride / 8;
    for (std::size_t r = 0; r < count; ++r) {
        const std::uint8_t* row = rows + r * stride;
        std::uint64_t sum = 0;
        for (std::size_t l = 0; l < lanes; ++l) {
            std::uint32_t sad = 0;
            for (std::size_t j = 8 * l; j < 8 * l + 8; ++j)
                sad += static_cast<std::uint32_t>(
                    std::abs(static_cast<int>(row[j]) - static_cast<int>(query[j])));
            sum += std::uint64_t{weight[l]} * sad;
        }
        bound[r] = (unit * static_cast<double>(sum) - row_error[r]) - query_error;
    }
}

#if ESF_KNN_X86

// GCC 12's AVX-512 headers start from _mm512_undefined_*() values and trip
// -Wmaybe-uninitialized once inlined (GCC bug 105593); the values are fully written.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

__attribute__((target("avx2"))) double exact_avx2(const float* a, const float* b, const float* w,
                                                  std::size_t n, double limit) {
    const __m256d sign = _mm256_set1_pd(-0.0);
    __m256d lo = _mm256_setzero_pd();  // lanes 0..3
    __m256d hi = _mm256_setzero_pd();  // lanes 4..7
    alignas(32) double lane[8];
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        if (i != 0 && i % detail::kExactCheck == 0) {
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

/// Exact conversion of 64-bit integers below 2^52 to double: (2^52 + x) - 2^52.
__attribute__((target("avx2"))) inline __m256d u52_to_double(__m256i x) {
    const __m256d magic = _mm256_set1_pd(4503599627370496.0);
    return _mm256_sub_pd(_mm256_castsi256_pd(_mm256_or_si256(x, _mm256_castpd_si256(magic))),
                         magic);
}

/// Four 64-bit partial sums per row: lane weights times SADs, over the whole row.
__attribute__((target("avx2"))) inline __m256i weighted_sad_avx2(const std::uint8_t* row,
                                                                 const std::uint8_t* query,
                                                                 const std::uint32_t* weight,
                                                                 std::size_t stride) {
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

__attribute__((target("avx2"))) inline __m256i load256(const std::uint8_t* at) {
    return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(at));
}

/// Transposed sums of four rows' lane sums ([a0+a1 b0+b1 | a2+a3 b2+b3], then across the
/// halves: [a b c d]), turned into bounds.
__attribute__((target("avx2"))) inline void store_bounds4(const __m256i* p, __m256d scale,
                                                          const double* row_error,
                                                          __m256d query_error, double* bound) {
    const __m256i t01 =
        _mm256_add_epi64(_mm256_unpacklo_epi64(p[0], p[1]), _mm256_unpackhi_epi64(p[0], p[1]));
    const __m256i t23 =
        _mm256_add_epi64(_mm256_unpacklo_epi64(p[2], p[3]), _mm256_unpackhi_epi64(p[2], p[3]));
    const __m256i total = _mm256_add_epi64(_mm256_permute2x128_si256(t01, t23, 0x20),
                                           _mm256_permute2x128_si256(t01, t23, 0x31));
    const __m256d estimate = _mm256_mul_pd(u52_to_double(total), scale);
    _mm256_storeu_pd(
        bound, _mm256_sub_pd(_mm256_sub_pd(estimate, _mm256_loadu_pd(row_error)), query_error));
}

__attribute__((target("avx2"))) void sketch_avx2(const std::uint8_t* rows, std::size_t count,
                                                 std::size_t stride, const std::uint8_t* query,
                                                 const std::uint32_t* weight, double unit,
                                                 const double* row_error, double query_error,
                                                 double* bound) {
    const __m256d scale = _mm256_set1_pd(unit);
    const __m256d error = _mm256_set1_pd(query_error);
    std::size_t r = 0;
    __m256i p[4];
    if (stride == 64) {  // two SADs per row: every default sketch up to 4096 dimensions
        const __m256i q0 = load256(query), q1 = load256(query + 32);
        const __m256i w0 =
            _mm256_cvtepu32_epi64(_mm_loadu_si128(reinterpret_cast<const __m128i*>(weight)));
        const __m256i w1 =
            _mm256_cvtepu32_epi64(_mm_loadu_si128(reinterpret_cast<const __m128i*>(weight + 4)));
        for (; r + 4 <= count; r += 4) {
            for (std::size_t i = 0; i < 4; ++i) {
                const std::uint8_t* row = rows + (r + i) * 64;
                p[i] =
                    _mm256_add_epi64(_mm256_mul_epu32(_mm256_sad_epu8(load256(row), q0), w0),
                                     _mm256_mul_epu32(_mm256_sad_epu8(load256(row + 32), q1), w1));
            }
            store_bounds4(p, scale, row_error + r, error, bound + r);
        }
    }
    for (; r + 4 <= count; r += 4) {
        for (std::size_t i = 0; i < 4; ++i)
            p[i] = weighted_sad_avx2(rows + (r + i) * stride, query, weight, stride);
        store_bounds4(p, scale, row_error + r, error, bound + r);
    }
    for (; r < count; ++r) {
        alignas(32) std::uint64_t part[4];
        _mm256_store_si256(reinterpret_cast<__m256i*>(part),
                           weighted_sad_avx2(rows + r * stride, query, weight, stride));
        const double estimate =
            unit * static_cast<double>((part[0] + part[1]) + (part[2] + part[3]));
        bound[r] = (estimate - row_error[r]) - query_error;
    }
}

__attribute__((target("avx512f,avx512bw"))) double exact_avx512(const float* a, const float* b,
                                                                const float* w, std::size_t n,
                                                                double limit) {
    __m512d acc = _mm512_setzero_pd();  // lanes 0..7
    alignas(64) double lane[8];
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        if (i != 0 && i % detail::kExactCheck == 0) {
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

/// Exact conversion of 64-bit integers below 2^52 to double: (2^52 + x) - 2^52.
__attribute__((target("avx512f,avx512bw"))) inline __m512d u52_to_double(__m512i x) {
    const __m512d magic = _mm512_set1_pd(4503599627370496.0);
    return _mm512_sub_pd(_mm512_castsi512_pd(_mm512_or_si512(x, _mm512_castpd_si512(magic))),
                         magic);
}

/// Eight 64-bit partial sums per row: lane weights times SADs, over the whole row.
__attribute__((target("avx512f,avx512bw"))) inline __m512i weighted_sad_avx512(
    const std::uint8_t* row, const std::uint8_t* query, const std::uint32_t* weight,
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
__attribute__((target("avx512f,avx512bw"))) inline __m512i pair_sums(__m512i a, __m512i b) {
    return _mm512_add_epi64(_mm512_unpacklo_epi64(a, b), _mm512_unpackhi_epi64(a, b));
}

/// Sums of 128-bit blocks: [a.0+a.1 | a.2+a.3 | b.0+b.1 | b.2+b.3].
__attribute__((target("avx512f,avx512bw"))) inline __m512i block_sums(__m512i a, __m512i b) {
    return _mm512_add_epi64(_mm512_shuffle_i64x2(a, b, _MM_SHUFFLE(2, 0, 2, 0)),
                            _mm512_shuffle_i64x2(a, b, _MM_SHUFFLE(3, 1, 3, 1)));
}

/// Transposed sums of eight rows' lane sums (row i's total in lane i), turned into bounds.
__attribute__((target("avx512f,avx512bw"))) inline void store_bounds8(
    const __m512i* p, __m512d scale, const double* row_error, __m512d query_error, double* bound) {
    const __m512i total = block_sums(block_sums(pair_sums(p[0], p[1]), pair_sums(p[2], p[3])),
                                     block_sums(pair_sums(p[4], p[5]), pair_sums(p[6], p[7])));
    const __m512d estimate = _mm512_mul_pd(u52_to_double(total), scale);
    _mm512_storeu_pd(
        bound, _mm512_sub_pd(_mm512_sub_pd(estimate, _mm512_loadu_pd(row_error)), query_error));
}

__attribute__((target("avx512f,avx512bw"))) void sketch_avx512(
    const std::uint8_t* rows, std::size_t count, std::size_t stride, const std::uint8_t* query,
    const std::uint32_t* weight, double unit, const double* row_error, double query_error,
    double* bound) {
    const __m512d scale = _mm512_set1_pd(unit);
    const __m512d error = _mm512_set1_pd(query_error);
    std::size_t r = 0;
    __m512i p[8];
    if (stride == 64) {  // one SAD per row: every default sketch up to 4096 dimensions
        const __m512i q = _mm512_loadu_si512(query);
        const __m512i w =
            _mm512_cvtepu32_epi64(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(weight)));
        for (; r + 8 <= count; r += 8) {
            for (std::size_t i = 0; i < 8; ++i)
                p[i] = _mm512_mul_epu32(_mm512_sad_epu8(_mm512_loadu_si512(rows + (r + i) * 64), q),
                                        w);
            store_bounds8(p, scale, row_error + r, error, bound + r);
        }
    }
    for (; r + 8 <= count; r += 8) {
        for (std::size_t i = 0; i < 8; ++i)
            p[i] = weighted_sad_avx512(rows + (r + i) * stride, query, weight, stride);
        store_bounds8(p, scale, row_error + r, error, bound + r);
    }
    for (; r < count; ++r) {
        const __m512i part = weighted_sad_avx512(rows + r * stride, query, weight, stride);
        const double estimate =
            unit * static_cast<double>(static_cast<std::uint64_t>(_mm512_reduce_add_epi64(part)));
        bound[r] = (estimate - row_error[r]) - query_error;
    }
}

#pragma GCC diagnostic pop

#endif  // ESF_KNN_X86

}  // namespace

namespace detail {

KnnKernels knn_kernels(KnnKernel kernel) {
    if (kernel == KnnKernel::kAuto) kernel = knn_best_kernel();
#if ESF_KNN_X86
    if (kernel == KnnKernel::kAvx512) return {exact_avx512, sketch_avx512};
    if (kernel == KnnKernel::kAvx2) return {exact_avx2, sketch_avx2};
#endif
    return {exact_scalar, sketch_scalar};
}

}  // namespace detail

const char* to_string(KnnKernel kernel) {
    switch (kernel) {
        case KnnKernel::kAuto:
            return "auto";
        case KnnKernel::kScalar:
            return "scalar";
        case KnnKernel::kAvx2:
            return "avx2";
        case KnnKernel::kAvx512:
            return "avx512";
    }
    return "?";
}

bool knn_kernel_supported(KnnKernel kernel) {
#if ESF_KNN_X86
    if (kernel == KnnKernel::kAvx512)
        return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw");
    if (kernel == KnnKernel::kAvx2) return __builtin_cpu_supports("avx2");
    return true;
#else
    return kernel == KnnKernel::kAuto || kernel == KnnKernel::kScalar;
#endif
}

KnnKernel knn_best_kernel() {
    if (knn_kernel_supported(KnnKernel::kAvx512)) return KnnKernel::kAvx512;
    if (knn_kernel_supported(KnnKernel::kAvx2)) return KnnKernel::kAvx2;
    return KnnKernel::kScalar;
}

}  // namespace esf
