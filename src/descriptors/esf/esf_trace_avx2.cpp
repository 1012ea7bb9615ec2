// The AVX2 line tracer (see esf_trace.hpp): 8 lines at a time, sorted by length.

#include <immintrin.h>

#include <algorithm>
#include <array>

#include "core/simd.hpp"
#include "descriptors/esf/esf_trace_kernels.hpp"

namespace esf::detail {

namespace {

/// For a counting sort by visited count: where the lines of each count start.
std::array<std::uint32_t, kGridSide + 1> length_offsets(std::span<const std::uint8_t> visited) {
    // Four interleaved tallies, summed after: runs of one length then do not wait on each other.
    std::array<std::array<std::uint32_t, kGridSide + 1>, 4> tally{};
    std::size_t i = 0;
    for (; i + 4 <= visited.size(); i += 4)
        for (std::size_t k = 0; k < 4; ++k) ++tally[k][visited[i + k]];
    for (; i < visited.size(); ++i) ++tally[0][visited[i]];
    std::array<std::uint32_t, kGridSide + 1> offsets{};
    for (std::size_t v = 0; v <= kGridSide; ++v)
        offsets[v] = tally[0][v] + tally[1][v] + tally[2][v] + tally[3][v];
    std::uint32_t sum = 0;
    for (auto& offset : offsets) {
        const std::uint32_t count = offset;
        offset = sum;
        sum += count;
    }
    return offsets;
}

/// Orders lines by visited count, so that the SIMD lanes of one group run equally long.
void sort_by_length(std::span<const std::uint8_t> visited, TraceScratch& scratch) {
    std::array<std::uint32_t, kGridSide + 1> bucket = length_offsets(visited);
    scratch.order.resize(visited.size());
    for (std::size_t i = 0; i < visited.size(); ++i)
        scratch.order[bucket[visited[i]]++] = static_cast<std::uint32_t>(i);
}

void visited_scalar(std::span<const std::uint32_t> starts, std::span<const std::uint32_t> ends,
                    std::span<std::uint8_t> visited) {
    for (std::size_t i = 0; i < starts.size(); ++i)
        visited[i] = static_cast<std::uint8_t>(visited_cells(starts[i], ends[i]));
}

}  // namespace

ESF_TARGET_AVX2 void trace_lines_avx2(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                                      std::span<const std::uint32_t> ends,
                                      std::span<std::uint32_t> occupied,
                                      std::span<std::uint8_t> visited, TraceScratch& scratch) {
    visited_scalar(starts, ends, visited);
    sort_by_length(visited, scratch);
    const auto* words32 = reinterpret_cast<const int*>(grid.words.data());
    const std::size_t count = starts.size();
    const __m256i zero = _mm256_setzero_si256(), one = _mm256_set1_epi32(1);
    const __m256i m63 = _mm256_set1_epi32(63), m31 = _mm256_set1_epi32(31);
    const __m256i all_cells = _mm256_set1_epi32(kGridSide * kGridSide * kGridSide - 1);
    alignas(32) std::int32_t lane_start[8], lane_end[8];
    for (std::size_t group = 0; group < count; group += 8) {
        const std::size_t lanes = std::min<std::size_t>(8, count - group);
        for (std::size_t k = 0; k < 8; ++k) {  // padding lanes repeat the last line
            const std::uint32_t id = scratch.order[group + std::min(k, lanes - 1)];
            lane_start[k] = static_cast<std::int32_t>(starts[id]);
            lane_end[k] = static_cast<std::int32_t>(ends[id]);
        }
        const __m256i s = _mm256_load_si256(reinterpret_cast<const __m256i*>(lane_start));
        const __m256i t = _mm256_load_si256(reinterpret_cast<const __m256i*>(lane_end));
        __m256i length[3], step[3];
        for (int k = 0; k < 3; ++k) {
            const int shift = k * kGridBits;
            const __m256i d = _mm256_sub_epi32(_mm256_and_si256(_mm256_srli_epi32(t, shift), m63),
                                               _mm256_and_si256(_mm256_srli_epi32(s, shift), m63));
            length[k] = _mm256_abs_epi32(d);
            step[k] = _mm256_sign_epi32(_mm256_set1_epi32(1 << shift), _mm256_or_si256(d, one));
        }
        // Masks are all-ones lanes; "a >= b" is "not (b > a)".
        const __m256i x_major =
            _mm256_andnot_si256(_mm256_or_si256(_mm256_cmpgt_epi32(length[1], length[0]),
                                                _mm256_cmpgt_epi32(length[2], length[0])),
                                _mm256_set1_epi32(-1));
        const __m256i y_major =
            _mm256_andnot_si256(_mm256_or_si256(x_major, _mm256_cmpgt_epi32(length[2], length[1])),
                                _mm256_set1_epi32(-1));
        const __m256i z_major =
            _mm256_andnot_si256(_mm256_or_si256(x_major, y_major), _mm256_set1_epi32(-1));
        const __m256i major_length =
            _mm256_max_epi32(_mm256_max_epi32(length[0], length[1]), length[2]);
        const __m256i major_step =
            _mm256_blendv_epi8(_mm256_blendv_epi8(step[2], step[1], y_major), step[0], x_major);
        const __m256i len1 = _mm256_blendv_epi8(length[0], length[1], x_major);
        const __m256i step1 = _mm256_blendv_epi8(step[0], step[1], x_major);
        const __m256i len2 = _mm256_blendv_epi8(length[2], length[1], z_major);
        const __m256i step2 = _mm256_blendv_epi8(step[2], step[1], z_major);
        const __m256i inc1 = _mm256_add_epi32(len1, len1), inc2 = _mm256_add_epi32(len2, len2);
        __m256i e1 = _mm256_sub_epi32(inc1, major_length),
                e2 = _mm256_sub_epi32(inc2, major_length);
        const __m256i dec = _mm256_add_epi32(major_length, major_length);
        const __m256i n = _mm256_max_epi32(major_length, one);
        const int longest = visited[scratch.order[group + lanes - 1]];
        const int shortest = visited[scratch.order[group]];
        __m256i cell = s, in = zero;
        for (int i = 0; i < longest; ++i) {
            const __m256i word = _mm256_i32gather_epi32(
                words32, _mm256_srli_epi32(_mm256_and_si256(cell, all_cells), 5), 4);
            __m256i bit =
                _mm256_and_si256(_mm256_srlv_epi32(word, _mm256_and_si256(cell, m31)), one);
            if (i >= shortest)
                bit = _mm256_and_si256(bit, _mm256_cmpgt_epi32(n, _mm256_set1_epi32(i)));
            in = _mm256_add_epi32(in, bit);
            const __m256i step_1 = _mm256_cmpgt_epi32(e1, zero);
            const __m256i step_2 = _mm256_cmpgt_epi32(e2, zero);
            cell = _mm256_add_epi32(
                _mm256_add_epi32(cell, major_step),
                _mm256_add_epi32(_mm256_and_si256(step_1, step1), _mm256_and_si256(step_2, step2)));
            e1 = _mm256_add_epi32(e1, _mm256_sub_epi32(inc1, _mm256_and_si256(step_1, dec)));
            e2 = _mm256_add_epi32(e2, _mm256_sub_epi32(inc2, _mm256_and_si256(step_2, dec)));
        }
        alignas(32) std::int32_t result[8];
        _mm256_store_si256(reinterpret_cast<__m256i*>(result), in);
        for (std::size_t k = 0; k < lanes; ++k)
            occupied[scratch.order[group + k]] = static_cast<std::uint32_t>(result[k]);
    }
}

}  // namespace esf::detail
