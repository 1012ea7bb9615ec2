// The AVX2 kernel of the histograms (see esf_triangles.hpp): two halves of 8 lanes.

#include <immintrin.h>

#include "core/simd.hpp"
#include "descriptors/esf/esf_triangle_kernels.hpp"

namespace esf::detail {

ESF_TARGET_AVX2 void histogram_block_avx2(const TriangleSet& set, const std::uint32_t* occupied,
                                          const std::uint8_t* visited, std::size_t first,
                                          float d2_scale, float d3_scale, HistogramBlock& block) {
    const std::size_t s = set.samples;
    const __m256i one = _mm256_set1_epi32(1), top = _mm256_set1_epi32(kTopBin);
    const __m256 half = _mm256_set1_ps(0.5f), top_f = _mm256_set1_ps(static_cast<float>(kTopBin));
    static_assert(kEsfBins == 64 && kHalf % kCopies == 0);
    const __m256i joint_base = _mm256_setr_epi32(
        joint_bin(0, 0, 0), joint_bin(1, 0, 0), joint_bin(2, 0, 0), joint_bin(3, 0, 0),
        joint_bin(4, 0, 0), joint_bin(5, 0, 0), joint_bin(6, 0, 0), joint_bin(7, 0, 0));
    for (int h = 0; h < 2; ++h) {
        const std::size_t t = first + static_cast<std::size_t>(kHalf * h);
        const int lane = kHalf * h;
        __m256i o[3], v[3];
        for (int k = 0; k < 3; ++k) {
            const std::size_t at = static_cast<std::size_t>(k) * s + t;
            o[k] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(occupied + at));
            v[k] = _mm256_cvtepu8_epi32(
                _mm_loadl_epi64(reinterpret_cast<const __m128i*>(visited + at)));
            // in: o + 1 >= v; out: not in and o <= 7; mixed: neither.
            const __m256i not_in = _mm256_cmpgt_epi32(v[k], _mm256_add_epi32(o[k], one));
            const __m256i out = _mm256_andnot_si256(
                _mm256_cmpgt_epi32(o[k], _mm256_set1_epi32(kLineOutMaxOccupied)), not_in);
            const __m256i mixed = _mm256_andnot_si256(out, not_in);
            const __m256 d = _mm256_loadu_ps(&set.d2[at]);
            const __m256i bin =
                _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_add_ps(
                                     _mm256_mul_ps(d, _mm256_set1_ps(d2_scale)), half)),
                                 top);
            const __m256i in_or_out =
                _mm256_add_epi32(bin, _mm256_blendv_epi8(_mm256_set1_epi32(6 * kEsfBins),
                                                         _mm256_set1_epi32(7 * kEsfBins), out));
            const __m256 ratio = _mm256_div_ps(_mm256_cvtepi32_ps(o[k]), _mm256_cvtepi32_ps(v[k]));
            const __m256i ratio_bin =
                _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(ratio, top_f), half));
            const __m256i joint = _mm256_add_epi32(
                _mm256_add_epi32(joint_base, _mm256_slli_epi32(bin, 6)), ratio_bin);
            _mm256_store_si256(reinterpret_cast<__m256i*>(block.bins[k] + lane),
                               _mm256_blendv_epi8(in_or_out, joint, mixed));
        }
        const __m256i occupied_sum = _mm256_add_epi32(_mm256_add_epi32(o[0], o[1]), o[2]);
        const __m256i visited_sum = _mm256_add_epi32(_mm256_add_epi32(v[0], v[1]), v[2]);
        // out: occupied_sum <= 21; in: not out and visited_sum - occupied_sum <= 3.
        const __m256i not_out =
            _mm256_cmpgt_epi32(occupied_sum, _mm256_set1_epi32(kTriangleOutMaxOccupied));
        const __m256i in =
            _mm256_andnot_si256(_mm256_cmpgt_epi32(_mm256_sub_epi32(visited_sum, occupied_sum),
                                                   _mm256_set1_epi32(kTriangleInMaxEmpty)),
                                not_out);
        __m256i cls = _mm256_blendv_epi8(_mm256_set1_epi32(64), _mm256_set1_epi32(2 * 64), not_out);
        cls = _mm256_andnot_si256(in, cls);
        const __m256 d3 = _mm256_loadu_ps(&set.d3[t]);
        const __m256i d3_bin = _mm256_min_epi32(
            _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(d3, _mm256_set1_ps(d3_scale)), half)),
            top);
        _mm256_store_si256(
            reinterpret_cast<__m256i*>(block.bins[3] + lane),
            _mm256_add_epi32(_mm256_add_epi32(cls, _mm256_set1_epi32(3 * 64)), d3_bin));
        const __m256i angles =
            _mm256_loadu_si256(reinterpret_cast<const __m256i*>(&set.angle_bins[t]));
        const __m256i byte = _mm256_set1_epi32(255);
        for (int k = 0; k < 3; ++k)
            _mm256_store_si256(
                reinterpret_cast<__m256i*>(block.bins[4 + k] + lane),
                _mm256_add_epi32(cls, _mm256_and_si256(_mm256_srli_epi32(angles, 8 * k), byte)));
        _mm256_store_si256(reinterpret_cast<__m256i*>(block.weight[0] + lane), v[2]);
        _mm256_store_si256(reinterpret_cast<__m256i*>(block.weight[1] + lane), v[0]);
        _mm256_store_si256(reinterpret_cast<__m256i*>(block.weight[2] + lane), v[1]);
    }
}

}  // namespace esf::detail
