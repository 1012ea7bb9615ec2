#include "esf_trace.hpp"

#include <immintrin.h>

#include "esf_simd.hpp"

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Vectors passed between this file's internal AVX-512 functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

#include <algorithm>
#include <cassert>
#include <cstdlib>

namespace esf::detail {

void VoxelGrid::dilate(int side) {
    // The 3x3x3 box is separable: dilate along x (bits), then y (rows), then z (slices).
    const std::uint64_t x_mask = side >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << side) - 1;
    for (auto& word : words) word = (word | (word << 1) | (word >> 1)) & x_mask;
    std::array<std::uint64_t, kGridWords> src = words;
    for (int z = 0; z < side; ++z) {
        for (int y = 0; y < side; ++y) {
            const int row = (z << kGridBits) | y;
            std::uint64_t word = src[static_cast<std::size_t>(row)];
            if (y > 0) word |= src[static_cast<std::size_t>(row - 1)];
            if (y + 1 < side) word |= src[static_cast<std::size_t>(row + 1)];
            words[static_cast<std::size_t>(row)] = word;
        }
    }
    src = words;
    for (int z = 0; z < side; ++z) {
        for (int y = 0; y < side; ++y) {
            const int row = (z << kGridBits) | y;
            std::uint64_t word = src[static_cast<std::size_t>(row)];
            if (z > 0) word |= src[static_cast<std::size_t>(row - kGridSide)];
            if (z + 1 < side) word |= src[static_cast<std::size_t>(row + kGridSide)];
            words[static_cast<std::size_t>(row)] = word;
        }
    }
}

namespace {

// The reference picks a major axis and steps the two minor axes on their error terms. Giving
// the major axis an error term too (2 L - L = L > 0, so it steps every cell and its term stays
// L) yields the same cells with one uniform rule for all three axes and no axis selection:
// per cell, each axis k steps when e_k > 0 (then e_k -= 2 L), and e_k += 2 a_k.

struct Axes {
    std::int32_t step[3];          // +-1, +-64, +-4096
    std::int32_t error[3];         // 2 a_k - L
    std::int32_t twice_length[3];  // 2 a_k
    std::int32_t twice_major;      // 2 L
    std::int32_t visited;          // max(L, 1)
};

inline Axes setup_line(std::uint32_t start, std::uint32_t end) {
    Axes line{};
    int length[3];
    for (int k = 0; k < 3; ++k) {
        const int shift = k * kGridBits;
        const int delta =
            static_cast<int>((end >> shift) & 63) - static_cast<int>((start >> shift) & 63);
        length[k] = delta < 0 ? -delta : delta;
        line.step[k] = (delta < 0 ? -1 : 1) * (1 << shift);
    }
    const int l = std::max({length[0], length[1], length[2]});
    for (int k = 0; k < 3; ++k) {
        line.error[k] = 2 * length[k] - l;
        line.twice_length[k] = 2 * length[k];
    }
    line.twice_major = 2 * l;
    line.visited = l > 0 ? l : 1;
    return line;
}

inline std::uint16_t trace_one(const VoxelGrid& grid, std::uint32_t start, const Axes& line) {
    std::uint32_t cell = start;
    std::int32_t e[3] = {line.error[0], line.error[1], line.error[2]};
    std::uint32_t occupied = 0;
    for (std::int32_t i = 0; i < line.visited; ++i) {
        occupied += grid.occupied(cell);
        for (int k = 0; k < 3; ++k) {
            const std::int32_t stepping = -static_cast<std::int32_t>(e[k] > 0);  // all ones or 0
            cell += static_cast<std::uint32_t>(line.step[k] & stepping);
            e[k] += line.twice_length[k] - (line.twice_major & stepping);
        }
    }
    return static_cast<std::uint16_t>(occupied);
}

/// Orders lines by visited count, so that the SIMD lanes of one group run equally long.
void sort_by_length(std::span<const std::uint8_t> visited, TraceScratch& scratch) {
    std::array<std::uint32_t, kGridSide + 1> bucket{};
    for (const std::uint8_t v : visited) ++bucket[v];
    std::uint32_t sum = 0;
    for (auto& b : bucket) {
        const std::uint32_t c = b;
        b = sum;
        sum += c;
    }
    scratch.order.resize(visited.size());
    for (std::size_t i = 0; i < visited.size(); ++i)
        scratch.order[bucket[visited[i]]++] = static_cast<std::uint32_t>(i);
}

void visited_scalar(std::span<const std::uint32_t> starts, std::span<const std::uint32_t> ends,
                    std::span<std::uint8_t> visited) {
    for (std::size_t i = 0; i < starts.size(); ++i)
        visited[i] = static_cast<std::uint8_t>(visited_cells(starts[i], ends[i]));
}

#define ESF_TARGET_AVX2 __attribute__((target("avx2,bmi2")))

ESF_TARGET_AVX512 void visited_avx512(std::span<const std::uint32_t> starts,
                                      std::span<const std::uint32_t> ends,
                                      std::span<std::uint8_t> visited) {
    const __m512i m63 = _mm512_set1_epi32(63), one = _mm512_set1_epi32(1);
    const std::size_t count = starts.size();
    std::size_t i = 0;
    for (; i + 16 <= count; i += 16) {
        const __m512i s = _mm512_loadu_si512(starts.data() + i);
        const __m512i t = _mm512_loadu_si512(ends.data() + i);
        __m512i longest = one;
        for (unsigned shift = 0; shift < 18; shift += 6) {
            const __m512i d = _mm512_sub_epi32(_mm512_and_si512(_mm512_srli_epi32(t, shift), m63),
                                               _mm512_and_si512(_mm512_srli_epi32(s, shift), m63));
            longest = _mm512_max_epi32(longest, _mm512_abs_epi32(d));
        }
        _mm_storeu_si128(reinterpret_cast<__m128i*>(visited.data() + i),
                         _mm512_cvtepi32_epi8(longest));
    }
    for (; i < count; ++i)
        visited[i] = static_cast<std::uint8_t>(visited_cells(starts[i], ends[i]));
}

// The SIMD kernels trace 16 (AVX-512) or 8 (AVX2) lines of equal or similar length at once,
// one line per lane. Lines are sorted by length, so a group runs min(n) cells without masks and
// only its few longer lanes run on with an activity mask. Gathers are never masked (slow on some
// CPUs): lanes past their end wrap their cell index into the grid and their bit is dropped.

// The AVX-512 kernel looks up two cells per gather and has no loop-carried error terms:
//
// - Closed form. After i cells the reference has stepped a minor axis of length a
//   q(i) = floor((2 a i + L - 1) / (2 L)) times (its error term starts at 2a - L, gains 2a per
//   cell and loses 2L per step). That is floor(i * a/L + (L - 1/2) / (2L)) exactly: the fraction
//   is never within 1/(4L) >= 1/252 of an integer, and the float evaluation (products of integers
//   below 2^13 by one rounded reciprocal, one fused multiply-add) errs by less than 1e-5.
// - Block table. Byte j of `blocks` (from kBlockPad) holds the 2x2x2 cells j + kBlockOffsets[k]
//   as bit k. Cells i and i+1 of a line differ by one step along each axis that moves, so both
//   lie in the block anchored at cell i minus one step along each axis the line walks down.

constexpr std::int32_t kBlockOffsets[8] = {0, 1, 64, 65, 4096, 4097, 4160, 4161};
constexpr std::int32_t kBlockPad = 4224;  // anchors reach down to cell -4161
constexpr std::int32_t kGridCells = kGridSide * kGridSide * kGridSide;

ESF_TARGET_AVX512 void build_blocks(const VoxelGrid& grid, std::vector<std::uint8_t>& blocks) {
    constexpr int kWordPad = kBlockPad / 64;  // 66 zero words before the grid, 66 after
    std::array<std::uint64_t, kWordPad + kGridWords + kWordPad> words{};
    std::copy(grid.words.begin(), grid.words.end(), words.begin() + kWordPad);
    blocks.resize(static_cast<std::size_t>(kBlockPad + kGridCells + 64));
    __m512i bit[8];
    for (int k = 0; k < 8; ++k) bit[k] = _mm512_set1_epi8(static_cast<char>(1 << k));
    for (int chunk = -kWordPad; chunk < kGridWords; ++chunk) {  // cells 64 chunk .. 64 chunk + 63
        const std::uint64_t* w = words.data() + kWordPad + chunk;
        __m512i acc = _mm512_setzero_si512();
        // Most rows of a view's grid are empty: so are their blocks.
        if ((w[0] | w[1] | w[2] | w[64] | w[65] | w[66]) != 0) {
            for (int k = 0; k < 8; ++k) {
                const int word = kBlockOffsets[k] / 64, shift = kBlockOffsets[k] % 64;
                const std::uint64_t plane =
                    shift == 0 ? w[word] : (w[word] >> 1) | (w[word + 1] << 63);
                acc = _mm512_or_si512(acc, _mm512_maskz_mov_epi8(plane, bit[k]));
            }
        }
        _mm512_storeu_si512(blocks.data() + kBlockPad + 64 * chunk, acc);
    }
}

struct PairLanes {
    __m512 start, major_step, step1, step2;  // cell index arithmetic, in float (exact: < 2^24)
    __m512 slope1, slope2, intercept;        // q(i) = floor(i * slope + intercept)
    __m512i anchor_offset, first_bit, major_flip, flip1, flip2, limit, occupied;
};

/// The value of the major axis, and of the first and second minor axis (x-major: y, z;
/// y-major: x, z; z-major: x, y) of each lane.
struct AxisRoles {
    __mmask16 x_major, y_major, z_major;
};

ESF_TARGET_AVX512 inline __m512i major_of(const AxisRoles& r, const __m512i* v) {
    return _mm512_mask_blend_epi32(r.x_major, _mm512_mask_blend_epi32(r.y_major, v[2], v[1]), v[0]);
}
ESF_TARGET_AVX512 inline __m512i minor1_of(const AxisRoles& r, const __m512i* v) {
    return _mm512_mask_blend_epi32(r.x_major, v[0], v[1]);
}
ESF_TARGET_AVX512 inline __m512i minor2_of(const AxisRoles& r, const __m512i* v) {
    return _mm512_mask_blend_epi32(r.z_major, v[2], v[1]);
}

ESF_TARGET_AVX512 PairLanes setup_pairs(__m512i s, __m512i t, bool skip_known) {
    const __m512i zero = _mm512_setzero_si512(), one = _mm512_set1_epi32(1);
    const __m512i m63 = _mm512_set1_epi32(63);
    __m512i length[3], step[3], block_bit[3];
    __m512i anchor_offset = zero, first_bit = zero;
    for (int k = 0; k < 3; ++k) {
        const unsigned shift = static_cast<unsigned>(k * kGridBits);
        const __m512i d = _mm512_sub_epi32(_mm512_and_si512(_mm512_srli_epi32(t, shift), m63),
                                           _mm512_and_si512(_mm512_srli_epi32(s, shift), m63));
        length[k] = _mm512_abs_epi32(d);
        const __m512i unit = _mm512_set1_epi32(1 << shift);
        const __mmask16 down = _mm512_cmplt_epi32_mask(d, zero);
        step[k] = _mm512_mask_sub_epi32(unit, down, zero, unit);
        block_bit[k] = _mm512_set1_epi32(1 << k);
        anchor_offset = _mm512_mask_sub_epi32(anchor_offset, down, anchor_offset, unit);
        first_bit = _mm512_mask_or_epi32(first_bit, down, first_bit, block_bit[k]);
    }
    const __mmask16 x_major = _mm512_cmpge_epi32_mask(length[0], length[1]) &
                              _mm512_cmpge_epi32_mask(length[0], length[2]);
    const __mmask16 y_major =
        static_cast<__mmask16>(~x_major & _mm512_cmpge_epi32_mask(length[1], length[2]));
    const __mmask16 z_major = static_cast<__mmask16>(~(x_major | y_major));
    const AxisRoles roles{x_major, y_major, z_major};
    const __m512i cells = _mm512_max_epi32(major_of(roles, length), one);  // visited: max(L, 1)
    const __m512 l = _mm512_cvtepi32_ps(cells);
    const __m512 half_per_cell = _mm512_div_ps(_mm512_set1_ps(0.5f), l);  // 1 / (2L)
    PairLanes lanes;
    lanes.start = _mm512_cvtepi32_ps(s);
    lanes.major_step = _mm512_cvtepi32_ps(major_of(roles, step));
    lanes.step1 = _mm512_cvtepi32_ps(minor1_of(roles, step));
    lanes.step2 = _mm512_cvtepi32_ps(minor2_of(roles, step));
    const __m512i a1 = minor1_of(roles, length), a2 = minor2_of(roles, length);
    lanes.slope1 = _mm512_mul_ps(_mm512_cvtepi32_ps(_mm512_add_epi32(a1, a1)), half_per_cell);
    lanes.slope2 = _mm512_mul_ps(_mm512_cvtepi32_ps(_mm512_add_epi32(a2, a2)), half_per_cell);
    lanes.intercept = _mm512_mul_ps(_mm512_sub_ps(l, _mm512_set1_ps(0.5f)), half_per_cell);
    lanes.anchor_offset = anchor_offset;
    lanes.first_bit = first_bit;
    lanes.major_flip = major_of(roles, block_bit);
    lanes.flip1 = minor1_of(roles, block_bit);
    lanes.flip2 = minor2_of(roles, block_bit);
    // With known ends, cells 0, 1 and L-1 count without a look-up and the walk covers 2..L-2.
    lanes.limit = skip_known ? _mm512_sub_epi32(cells, one) : cells;
    lanes.occupied = skip_known ? _mm512_min_epi32(cells, _mm512_set1_epi32(3)) : zero;
    return lanes;
}

/// Cells i and i+1 of every lane (lanes past their end masked when `tail`).
template <bool tail>
ESF_TARGET_AVX512 inline void trace_pair(PairLanes& lanes, const int* blocks, int i) {
    constexpr int kFloor = _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC;
    const __m512 fi = _mm512_set1_ps(static_cast<float>(i));
    const __m512 fi1 = _mm512_set1_ps(static_cast<float>(i + 1));
    const __m512 q1 =
        _mm512_roundscale_ps(_mm512_fmadd_ps(fi, lanes.slope1, lanes.intercept), kFloor);
    const __m512 q2 =
        _mm512_roundscale_ps(_mm512_fmadd_ps(fi, lanes.slope2, lanes.intercept), kFloor);
    const __m512 next1 =
        _mm512_roundscale_ps(_mm512_fmadd_ps(fi1, lanes.slope1, lanes.intercept), kFloor);
    const __m512 next2 =
        _mm512_roundscale_ps(_mm512_fmadd_ps(fi1, lanes.slope2, lanes.intercept), kFloor);
    const __m512 position = _mm512_fmadd_ps(
        q2, lanes.step2,
        _mm512_fmadd_ps(q1, lanes.step1, _mm512_fmadd_ps(fi, lanes.major_step, lanes.start)));
    __m512i cell = _mm512_cvttps_epi32(position);
    if (tail) cell = _mm512_and_si512(cell, _mm512_set1_epi32(kGridCells - 1));
    const __m512i block =
        _mm512_mask_i32gather_epi32(_mm512_setzero_si512(), static_cast<__mmask16>(0xffff),
                                    _mm512_add_epi32(cell, lanes.anchor_offset), blocks, 1);
    __m512i next_bit = _mm512_mask_or_epi32(lanes.major_flip, _mm512_cmpneq_ps_mask(q1, next1),
                                            lanes.major_flip, lanes.flip1);
    next_bit =
        _mm512_mask_or_epi32(next_bit, _mm512_cmpneq_ps_mask(q2, next2), next_bit, lanes.flip2);
    next_bit = _mm512_xor_si512(next_bit, lanes.first_bit);
    const __m512i one = _mm512_set1_epi32(1);
    __mmask16 first = _mm512_test_epi32_mask(block, _mm512_sllv_epi32(one, lanes.first_bit));
    __mmask16 second = _mm512_test_epi32_mask(block, _mm512_sllv_epi32(one, next_bit));
    if (tail) {
        first &= _mm512_cmpgt_epi32_mask(lanes.limit, _mm512_set1_epi32(i));
        second &= _mm512_cmpgt_epi32_mask(lanes.limit, _mm512_set1_epi32(i + 1));
    }
    lanes.occupied = _mm512_mask_add_epi32(lanes.occupied, first, lanes.occupied, one);
    lanes.occupied = _mm512_mask_add_epi32(lanes.occupied, second, lanes.occupied, one);
}

ESF_TARGET_AVX512 void trace_lines_avx512(const VoxelGrid& grid,
                                          std::span<const std::uint32_t> starts,
                                          std::span<const std::uint32_t> ends,
                                          std::span<std::uint16_t> occupied,
                                          std::span<std::uint8_t> visited, TraceScratch& scratch,
                                          bool skip_known) {
    visited_avx512(starts, ends, visited);
    sort_by_length(visited, scratch);
    build_blocks(grid, scratch.blocks);
    const auto* blocks = reinterpret_cast<const int*>(scratch.blocks.data() + kBlockPad);
    const auto* start32 = reinterpret_cast<const int*>(starts.data());
    const auto* end32 = reinterpret_cast<const int*>(ends.data());
    const std::size_t count = starts.size();
    const int first_cell = skip_known ? 2 : 0, end_skip = skip_known ? 1 : 0;
    const __m512i zero = _mm512_setzero_si512();
    // Two groups of 16 lines at once: their gathers overlap, and a loop serves 32 lines.
    constexpr std::size_t kGroup = 32;
    for (std::size_t group = 0; group < count; group += kGroup) {
        const std::size_t size = std::min(kGroup, count - group);
        const std::size_t size_a = std::min<std::size_t>(16, size), size_b = size - size_a;
        const auto live_a = static_cast<__mmask16>((1u << size_a) - 1u);
        const auto live_b = static_cast<__mmask16>((1u << size_b) - 1u);
        const std::uint32_t* ids = scratch.order.data() + group;
        const __m512i ids_a = _mm512_maskz_loadu_epi32(live_a, ids);
        const __m512i ids_b = _mm512_maskz_loadu_epi32(live_b, ids + 16);
        PairLanes a =
            setup_pairs(_mm512_mask_i32gather_epi32(zero, live_a, ids_a, start32, 4),
                        _mm512_mask_i32gather_epi32(zero, live_a, ids_a, end32, 4), skip_known);
        PairLanes b =
            setup_pairs(_mm512_mask_i32gather_epi32(zero, live_b, ids_b, start32, 4),
                        _mm512_mask_i32gather_epi32(zero, live_b, ids_b, end32, 4), skip_known);
        const int shortest = visited[ids[0]] - end_skip;
        const int longest = visited[ids[size - 1]] - end_skip;
        int i = first_cell;
        for (; i + 1 < shortest; i += 2) {
            trace_pair<false>(a, blocks, i);
            trace_pair<false>(b, blocks, i);
        }
        for (; i < longest; i += 2) {
            trace_pair<true>(a, blocks, i);
            trace_pair<true>(b, blocks, i);
        }
        alignas(64) std::uint32_t result[kGroup];
        _mm512_store_si512(result, a.occupied);
        _mm512_store_si512(result + 16, b.occupied);
        for (std::size_t k = 0; k < size; ++k)
            occupied[ids[k]] = static_cast<std::uint16_t>(result[k]);
    }
}

ESF_TARGET_AVX2 void trace_lines_avx2(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                                      std::span<const std::uint32_t> ends,
                                      std::span<std::uint16_t> occupied,
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
            occupied[scratch.order[group + k]] = static_cast<std::uint16_t>(result[k]);
    }
}

enum class Kernel { kScalar, kAvx2, kAvx512 };

Kernel best_kernel() {
    if (esf_avx512_available()) return Kernel::kAvx512;
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("bmi2")) return Kernel::kAvx2;
    return Kernel::kScalar;
}

}  // namespace

void trace_lines_scalar(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                        std::span<const std::uint32_t> ends, std::span<std::uint16_t> occupied,
                        std::span<std::uint8_t> visited) {
    assert(starts.size() == ends.size() && occupied.size() == starts.size());
    for (std::size_t i = 0; i < starts.size(); ++i) {
        const Axes line = setup_line(starts[i], ends[i]);
        occupied[i] = trace_one(grid, starts[i], line);
        visited[i] = static_cast<std::uint8_t>(line.visited);
    }
}

void trace_lines(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                 std::span<const std::uint32_t> ends, std::span<std::uint16_t> occupied,
                 std::span<std::uint8_t> visited, TraceScratch& scratch, TraceKernel kernel,
                 LineEnds line_ends) {
    assert(starts.size() == ends.size() && occupied.size() == starts.size() &&
           visited.size() == starts.size());
    static const Kernel best = best_kernel();  // CPU features do not change while running
    Kernel use = best;
    if (kernel == TraceKernel::kScalar) use = Kernel::kScalar;
    if (kernel == TraceKernel::kAvx2 && best != Kernel::kScalar) use = Kernel::kAvx2;
    switch (use) {
        case Kernel::kAvx512:
            trace_lines_avx512(grid, starts, ends, occupied, visited, scratch,
                               line_ends == LineEnds::kSetBeforeDilation);
            break;
        case Kernel::kAvx2:
            trace_lines_avx2(grid, starts, ends, occupied, visited, scratch);
            break;
        case Kernel::kScalar:
            trace_lines_scalar(grid, starts, ends, occupied, visited);
            break;
    }
}

const char* trace_kernel_name() {
    switch (best_kernel()) {
        case Kernel::kAvx512:
            return "avx512";
        case Kernel::kAvx2:
            return "avx2";
        default:
            return "scalar";
    }
}

}  // namespace esf::detail
