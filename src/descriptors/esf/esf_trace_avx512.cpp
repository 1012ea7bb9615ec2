// The AVX-512 line tracer (see esf_trace.hpp): 16 lines of one length at a time, three cells
// per look-up in a table of 3x3x3 cubes.

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <bit>

#include "core/simd.hpp"
#include "descriptors/esf/esf_cube_table.hpp"
#include "descriptors/esf/esf_trace_kernels.hpp"

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Vectors passed between this file's internal functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace esf::detail {

namespace {

/// Visited counts of all lines and their records (line_record()), 16 at a time, bucketed by
/// visited count (LineChunker).
ESF_TARGET_AVX512 std::size_t bucket_lines_avx512(std::span<const std::uint32_t> starts,
                                                  std::span<const std::uint32_t> ends,
                                                  std::span<std::uint8_t> visited,
                                                  TraceScratch& scratch) {
    const __m512i m63 = _mm512_set1_epi32(63), one = _mm512_set1_epi32(1);
    const std::size_t count = starts.size();
    // A block of lines at a time: every line's count and record, 16 at a time, then the
    // block's records into their chunks (reading the vector stores back at once would stall on
    // store forwarding).
    LineChunker chunker(count, scratch);
    std::vector<std::uint64_t>& records = scratch.records;
    records.resize(kRecordBlockLines);
    const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    // Records 0-7 and 8-15: the low and high words of each line side by side.
    const __m512i first_eight =
        _mm512_setr_epi32(0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23);
    const __m512i last_eight = _mm512_add_epi32(first_eight, _mm512_set1_epi32(8));
    const __m512i line_part = _mm512_set1_epi32(static_cast<int>(kLinePartMask));
    for (std::size_t first = 0; first < count; first += kRecordBlockLines) {
        const std::size_t last = std::min(count, first + kRecordBlockLines);
        std::size_t i = first;
        for (; i + 16 <= last; i += 16) {
            const __m512i s = _mm512_loadu_si512(starts.data() + i);
            const __m512i t = _mm512_loadu_si512(ends.data() + i);
            __m512i longest = one;
            for (unsigned shift = 0; shift < 18; shift += 6) {
                const __m512i d =
                    _mm512_sub_epi32(_mm512_and_si512(_mm512_srli_epi32(t, shift), m63),
                                     _mm512_and_si512(_mm512_srli_epi32(s, shift), m63));
                longest = _mm512_max_epi32(longest, _mm512_abs_epi32(d));
            }
            _mm_storeu_si128(reinterpret_cast<__m128i*>(visited.data() + i),
                             _mm512_cvtepi32_epi8(longest));
            const __m512i line = _mm512_add_epi32(lane, _mm512_set1_epi32(static_cast<int>(i)));
            const __m512i low =
                _mm512_or_si512(s, _mm512_slli_epi32(_mm512_and_si512(line, line_part), kCellBits));
            const __m512i high = _mm512_or_si512(
                t, _mm512_slli_epi32(_mm512_srli_epi32(line, kLinePartBits), kCellBits));
            _mm512_storeu_si512(records.data() + (i - first),
                                _mm512_permutex2var_epi32(low, first_eight, high));
            _mm512_storeu_si512(records.data() + (i - first) + 8,
                                _mm512_permutex2var_epi32(low, last_eight, high));
        }
        for (; i < last; ++i) {
            visited[i] = static_cast<std::uint8_t>(visited_cells(starts[i], ends[i]));
            records[i - first] = line_record(starts[i], ends[i], i);
        }
        chunker.add(visited.data() + first, records.data(), last - first);
    }
    return chunker.finish();
}

// The AVX-512 kernel looks up three cells per gathered element (gathers move about one element
// per cycle: their element count sets its speed) and has no loop-carried error terms:
//
// - Closed form. After i cells the reference has stepped a minor axis of length a
//   q(i) = floor((2 a i + L - 1) / (2 L)) times (its error term starts at 2a - L, gains 2a per
//   cell and loses 2L per step). That is floor(v(i)), v(i) = i * a/L + (L - 1/2) / (2L), exactly:
//   v(i) is never within 1/(4L) >= 1/252 of an integer. The float evaluation (v at the first
//   cell by one fused multiply-add of rounded slopes, then sums of 3 a/L per 3 cells) errs by
//   less than 1e-4 after 64 cells. The steps to cells i+1 and i+2 follow from r = v(i) - q(i)
//   (exact in float): n = q(i+1) - q(i) = [r >= 1 - a/L] and q(i+2) - q(i+1) =
//   [r >= 1 - 2a/L + n], both with that margin.
// - Cube table. Entry j of `cubes` (from kCubePad) holds the 3x3x3 cells j + dx + 64 dy + 4096 dz
//   as bit dx + 3 dy + 9 dz. Cells i, i+1 and i+2 of a line lie within two steps of cell i along
//   each axis, in its direction, so all three lie in the cube anchored at cell i minus two steps
//   along each axis the line walks down.

/// Cells x + dx (dx = 0, 1, 2) of a word `low` for x = 0 .. 63, as bits dx of 64 bytes. Past
/// x = 63 the cells continue into the next word, `high` (the cube table is linear).
ESF_TARGET_AVX512 inline __m512i cell_triples(std::uint64_t low, std::uint64_t high) {
    const __m512i one = _mm512_set1_epi8(1), two = _mm512_set1_epi8(2);
    const __m512i four = _mm512_set1_epi8(4);
    return _mm512_ternarylogic_epi32(_mm512_maskz_mov_epi8(low, one),
                                     _mm512_maskz_mov_epi8((low >> 1) | (high << 63), two),
                                     _mm512_maskz_mov_epi8((low >> 2) | (high << 62), four), 0xfe);
}

// The row kernels of the cube table (esf_cube_table.inl).
ESF_TARGET_AVX512 inline std::uint64_t words_with_cells(const std::uint64_t* words) {
    std::uint64_t bits = 0;
    for (int j = 0; j < 64; j += 8) {
        const __m512i v = _mm512_loadu_si512(words + j);
        bits |= std::uint64_t{_mm512_test_epi64_mask(v, v)} << j;
    }
    return bits;
}
ESF_TARGET_AVX512 inline void form_triples(std::uint64_t low, std::uint64_t high,
                                           std::uint16_t* row) {
    const __m512i bytes = cell_triples(low, high);
    _mm512_store_si512(row, _mm512_cvtepu8_epi16(_mm512_castsi512_si256(bytes)));
    _mm512_store_si512(row + 32, _mm512_cvtepu8_epi16(_mm512_extracti64x4_epi64(bytes, 1)));
}
ESF_TARGET_AVX512 inline void form_squares(const std::uint16_t* t0, const std::uint16_t* t1,
                                           const std::uint16_t* t2, std::uint16_t* row) {
    for (int h = 0; h < 64; h += 32)
        _mm512_store_si512(
            row + h, _mm512_ternarylogic_epi32(
                         _mm512_load_si512(t0 + h), _mm512_slli_epi16(_mm512_load_si512(t1 + h), 3),
                         _mm512_slli_epi16(_mm512_load_si512(t2 + h), 6), 0xfe));
}
ESF_TARGET_AVX512 inline void form_cubes(const std::uint16_t* s0, const std::uint16_t* s1,
                                         const std::uint16_t* s2, std::uint32_t* entries) {
    const auto part = [](const std::uint16_t* s, int j) ESF_TARGET_AVX512 {
        return _mm512_cvtepu16_epi32(
            _mm256_load_si256(reinterpret_cast<const __m256i*>(s + 16 * j)));
    };
    for (int j = 0; j < 4; ++j)
        _mm512_storeu_si512(entries + 16 * j, _mm512_ternarylogic_epi32(
                                                  part(s0, j), _mm512_slli_epi32(part(s1, j), 9),
                                                  _mm512_slli_epi32(part(s2, j), 18), 0xfe));
}
ESF_TARGET_AVX512 inline void clear_cubes(std::uint32_t* entries) {
    for (int j = 0; j < 4; ++j) _mm512_storeu_si512(entries + 16 * j, _mm512_setzero_si512());
}

#define ESF_CUBE_TABLE_TARGET ESF_TARGET_AVX512
#include "descriptors/esf/esf_cube_table.inl"
#undef ESF_CUBE_TABLE_TARGET

// Two builds of the group loop: with VPOPCNTD (Ice Lake, Zen 4 and later) and without.
namespace plain {
#define ESF_CUBE_TARGET ESF_TARGET_AVX512
#define ESF_CUBE_POPCNT 0
#include "descriptors/esf/esf_trace_cubes.inl"
#undef ESF_CUBE_TARGET
#undef ESF_CUBE_POPCNT
}  // namespace plain

namespace popcnt {
#define ESF_CUBE_TARGET ESF_TARGET_AVX512_VPOPCNTDQ
#define ESF_CUBE_POPCNT 1
#include "descriptors/esf/esf_trace_cubes.inl"
#undef ESF_CUBE_TARGET
#undef ESF_CUBE_POPCNT
}  // namespace popcnt

}  // namespace

ESF_TARGET_AVX512 void trace_lines_avx512(const VoxelGrid& grid,
                                          std::span<const std::uint32_t> starts,
                                          std::span<const std::uint32_t> ends,
                                          std::span<std::uint32_t> occupied,
                                          std::span<std::uint8_t> visited, TraceScratch& scratch,
                                          bool skip_known, bool with_popcount) {
    const std::size_t chunks = bucket_lines_avx512(starts, ends, visited, scratch);
    build_cubes(grid, scratch);
    const std::uint32_t* cubes = scratch.cubes.data() + kCubePad;
    if (with_popcount)
        popcnt::trace_groups(cubes, scratch, chunks, occupied.data(), skip_known);
    else
        plain::trace_groups(cubes, scratch, chunks, occupied.data(), skip_known);
}

}  // namespace esf::detail
