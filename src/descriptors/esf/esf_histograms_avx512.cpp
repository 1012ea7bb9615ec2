// The AVX-512 kernel of the histograms (see esf_triangles.hpp).

#include <immintrin.h>

#include <array>

#include "core/simd.hpp"
#include "descriptors/esf/esf_triangle_kernels.hpp"

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Vectors passed between this file's internal functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace esf::detail {

namespace {

/// 1/v for v = 1 .. 64, rounded to nearest.
constexpr std::array<float, 64> reciprocal_table() {
    std::array<float, 64> table{};
    for (int v = 1; v <= 64; ++v)
        table[static_cast<std::size_t>(v - 1)] = 1.0f / static_cast<float>(v);
    return table;
}
alignas(64) constexpr std::array<float, 64> kReciprocal = reciprocal_table();

/// o / v for whole numbers 0 <= o <= 64 and 1 <= v <= 64, equal to the rounded division without
/// the divider (slow for 16 lanes): the product by the rounded reciprocal y, corrected by its
/// remainder, q + (o - q v) y. A test compares it with division for every such pair.
ESF_TARGET_AVX512 inline __m512 small_ratio16(__m512i o, __m512i v) {
    const __m512i slot = _mm512_sub_epi32(v, _mm512_set1_epi32(1));
    const __m512 y =
        _mm512_mask_blend_ps(_mm512_cmpge_epi32_mask(slot, _mm512_set1_epi32(32)),
                             _mm512_permutex2var_ps(_mm512_load_ps(kReciprocal.data()), slot,
                                                    _mm512_load_ps(kReciprocal.data() + 16)),
                             _mm512_permutex2var_ps(_mm512_load_ps(kReciprocal.data() + 32), slot,
                                                    _mm512_load_ps(kReciprocal.data() + 48)));
    const __m512 a = _mm512_cvtepi32_ps(o), b = _mm512_cvtepi32_ps(v);
    const __m512 q = _mm512_mul_ps(a, y);
    return _mm512_fmadd_ps(_mm512_fnmadd_ps(q, b, a), y, q);
}

}  // namespace

ESF_TARGET_AVX512 void histogram_block_avx512(const TriangleSet& set, const std::uint32_t* occupied,
                                              const std::uint8_t* visited, std::size_t t,
                                              float d2_scale, float d3_scale,
                                              HistogramBlock& block) {
    const std::size_t s = set.samples;
    const __m512i one = _mm512_set1_epi32(1), top = _mm512_set1_epi32(kTopBin);
    const __m512 half = _mm512_set1_ps(0.5f), top_f = _mm512_set1_ps(static_cast<float>(kTopBin));
    static_assert(kEsfBins == 64 && kLanes % kCopies == 0);
    const __m512i joint_base = _mm512_setr_epi32(
        joint_bin(0, 0, 0), joint_bin(1, 0, 0), joint_bin(2, 0, 0), joint_bin(3, 0, 0),
        joint_bin(4, 0, 0), joint_bin(5, 0, 0), joint_bin(6, 0, 0), joint_bin(7, 0, 0),
        joint_bin(8, 0, 0), joint_bin(9, 0, 0), joint_bin(10, 0, 0), joint_bin(11, 0, 0),
        joint_bin(12, 0, 0), joint_bin(13, 0, 0), joint_bin(14, 0, 0), joint_bin(15, 0, 0));
    __m512i o[3], v[3];
    for (int k = 0; k < 3; ++k) {
        const std::size_t at = static_cast<std::size_t>(k) * s + t;
        o[k] = _mm512_loadu_si512(occupied + at);
        v[k] =
            _mm512_cvtepu8_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(visited + at)));
        const __mmask16 in = _mm512_cmpge_epi32_mask(_mm512_add_epi32(o[k], one), v[k]);
        const __mmask16 out = static_cast<__mmask16>(
            ~in & _mm512_cmple_epi32_mask(o[k], _mm512_set1_epi32(kLineOutMaxOccupied)));
        const __mmask16 mixed = static_cast<__mmask16>(~in & ~out);
        const __m512 d = _mm512_loadu_ps(&set.d2[at]);
        const __m512i bin = _mm512_min_epi32(
            _mm512_cvttps_epi32(_mm512_add_ps(_mm512_mul_ps(d, _mm512_set1_ps(d2_scale)), half)),
            top);
        const __m512i in_or_out =
            _mm512_mask_add_epi32(_mm512_add_epi32(bin, _mm512_set1_epi32(6 * kEsfBins)), out, bin,
                                  _mm512_set1_epi32(7 * kEsfBins));
        const __m512i ratio_bin = _mm512_cvttps_epi32(
            _mm512_add_ps(_mm512_mul_ps(small_ratio16(o[k], v[k]), top_f), half));
        const __m512i joint =
            _mm512_add_epi32(_mm512_add_epi32(joint_base, _mm512_slli_epi32(bin, 6)), ratio_bin);
        _mm512_store_si512(block.bins[k], _mm512_mask_mov_epi32(in_or_out, mixed, joint));
    }
    const __m512i occupied_sum = _mm512_add_epi32(_mm512_add_epi32(o[0], o[1]), o[2]);
    const __m512i visited_sum = _mm512_add_epi32(_mm512_add_epi32(v[0], v[1]), v[2]);
    const __mmask16 out =
        _mm512_cmple_epi32_mask(occupied_sum, _mm512_set1_epi32(kTriangleOutMaxOccupied));
    const __mmask16 in = static_cast<__mmask16>(
        ~out & _mm512_cmple_epi32_mask(_mm512_sub_epi32(visited_sum, occupied_sum),
                                       _mm512_set1_epi32(kTriangleInMaxEmpty)));
    __m512i cls = _mm512_set1_epi32(2 * 64);
    cls = _mm512_mask_mov_epi32(cls, out, _mm512_set1_epi32(64));
    cls = _mm512_mask_mov_epi32(cls, in, _mm512_setzero_si512());
    const __m512 d3 = _mm512_loadu_ps(&set.d3[t]);
    const __m512i d3_bin = _mm512_min_epi32(
        _mm512_cvttps_epi32(_mm512_add_ps(_mm512_mul_ps(d3, _mm512_set1_ps(d3_scale)), half)), top);
    _mm512_store_si512(block.bins[3],
                       _mm512_add_epi32(_mm512_add_epi32(cls, _mm512_set1_epi32(3 * 64)), d3_bin));
    const __m512i angles = _mm512_loadu_si512(&set.angle_bins[t]);
    const __m512i byte = _mm512_set1_epi32(255);
    for (int k = 0; k < 3; ++k)
        _mm512_store_si512(
            block.bins[4 + k],
            _mm512_add_epi32(cls, _mm512_and_si512(_mm512_srli_epi32(angles, 8 * k), byte)));
    _mm512_store_si512(block.weight[0], v[2]);
    _mm512_store_si512(block.weight[1], v[0]);
    _mm512_store_si512(block.weight[2], v[1]);
}

ESF_TARGET_AVX512 void small_ratios_avx512(const std::uint32_t* o, const std::uint32_t* v,
                                           float* out, std::size_t count) {
    for (std::size_t i = 0; i < count; i += kLanes) {
        const auto live = static_cast<__mmask16>(
            count - i >= kLanes ? 0xffffu : (1u << static_cast<unsigned>(count - i)) - 1u);
        const __m512i occupied = _mm512_maskz_loadu_epi32(live, o + i);
        const __m512i visited =
            _mm512_mask_loadu_epi32(_mm512_set1_epi32(1), live, v + i);  // 1: no lookup past 64
        _mm512_mask_storeu_ps(out + i, live, small_ratio16(occupied, visited));
    }
}

}  // namespace esf::detail
