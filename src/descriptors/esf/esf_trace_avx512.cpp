// The AVX-512 line tracer (see esf_trace.hpp): 16 lines of one length at a time, three cells
// per look-up in a table of 3x3x3 cubes.

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <bit>

#include "core/simd.hpp"
#include "descriptors/esf/esf_trace_kernels.hpp"

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Vectors passed between this file's internal functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace esf::detail {

namespace {

/// Lines per chunk of bucket_lines_avx512(): a multiple of the 16 lanes of a group.
constexpr std::uint32_t kChunkLines = 256;

/// Visited counts of all lines, and their records (start | end << kEndShift | line <<
/// kLineShift) bucketed by visited count: each count fills chunks of kChunkLines records taken
/// in turn from one pool, so every group of 16 in a chunk has lines of one length. Chunks are
/// numbered in the order they are opened; each count's last chunk may be partly filled
/// (chunk_size). Unlike a counting sort, no tally of the counts is needed first.
ESF_TARGET_AVX512 std::size_t bucket_lines_avx512(std::span<const std::uint32_t> starts,
                                                  std::span<const std::uint32_t> ends,
                                                  std::span<std::uint8_t> visited,
                                                  TraceScratch& scratch) {
    const __m512i m63 = _mm512_set1_epi32(63), one = _mm512_set1_epi32(1);
    const std::size_t count = starts.size();
    // Every chunk is full but each count's last: at most count / kChunkLines + kGridSide + 1.
    const std::size_t most_chunks = count / kChunkLines + kGridSide + 1;
    scratch.chunked.resize(most_chunks * kChunkLines);
    scratch.chunk_visited.resize(most_chunks);
    scratch.chunk_size.resize(most_chunks);
    std::uint64_t* const pool = scratch.chunked.data();
    // Per count: where its next record goes (0: no chunk yet). A count whose next place starts
    // a chunk has filled its chunk (or has none) and opens the next free one.
    std::array<std::uint32_t, kGridSide + 1> next{};
    std::uint32_t chunks = 0;
    const auto put = [&](std::uint32_t v, std::uint64_t record) {
        std::uint32_t at = next[v];
        if (at % kChunkLines == 0) {  // one record in kChunkLines
            scratch.chunk_visited[chunks] = static_cast<std::uint8_t>(v);
            at = chunks++ * kChunkLines;
        }
        pool[at] = record;
        next[v] = at + 1;
    };
    // First every line's count and record, 16 at a time; then the records into their chunks
    // (reading the vector stores back at once would stall on store forwarding).
    std::vector<std::uint64_t>& records = scratch.records;
    records.resize(count);
    const __m512i lane = _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7);
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
        for (int half = 0; half < 2; ++half) {
            const __m256i s8 = half ? _mm512_extracti64x4_epi64(s, 1) : _mm512_castsi512_si256(s);
            const __m256i t8 = half ? _mm512_extracti64x4_epi64(t, 1) : _mm512_castsi512_si256(t);
            const __m512i line = _mm512_slli_epi64(
                _mm512_add_epi64(lane, _mm512_set1_epi64(static_cast<long long>(i + 8 * half))),
                kLineShift);
            _mm512_storeu_si512(
                records.data() + i + 8 * half,
                _mm512_or_si512(
                    _mm512_or_si512(_mm512_cvtepu32_epi64(s8),
                                    _mm512_slli_epi64(_mm512_cvtepu32_epi64(t8), kEndShift)),
                    line));
        }
    }
    for (; i < count; ++i) {
        visited[i] = static_cast<std::uint8_t>(visited_cells(starts[i], ends[i]));
        records[i] =
            starts[i] | std::uint64_t{ends[i]} << kEndShift | std::uint64_t{i} << kLineShift;
    }
    for (i = 0; i < count; ++i) put(visited[i], records[i]);
    for (std::uint32_t c = 0; c < chunks; ++c) scratch.chunk_size[c] = kChunkLines;
    for (const std::uint32_t at : next)  // each count's last chunk, full or not
        if (at != 0) scratch.chunk_size[(at - 1) / kChunkLines] = (at - 1) % kChunkLines + 1;
    return chunks;
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

constexpr std::int32_t kGridCells = kGridSide * kGridSide * kGridSide;
constexpr std::int32_t kCubePad = 8448;  // anchors reach down to cell -(2 + 2 * 64 + 2 * 4096)
constexpr int kCubeWordPad = kCubePad / 64;

/// 1 / (2L) for L = 1 .. 64 (the AVX-512 kernel's slope set-up).
constexpr std::array<float, 64> half_per_cell_table() {
    std::array<float, 64> table{};
    for (int l = 1; l <= 64; ++l)
        table[static_cast<std::size_t>(l - 1)] = 0.5f / static_cast<float>(l);
    return table;
}
alignas(64) constexpr std::array<float, 64> kHalfPerCell = half_per_cell_table();

/// Cells x + dx (dx = 0, 1, 2) of a word `low` for x = 0 .. 63, as bits dx of 64 bytes. Past
/// x = 63 the cells continue into the next word, `high` (the cube table is linear).
ESF_TARGET_AVX512 inline __m512i cell_triples(std::uint64_t low, std::uint64_t high) {
    const __m512i one = _mm512_set1_epi8(1), two = _mm512_set1_epi8(2);
    const __m512i four = _mm512_set1_epi8(4);
    return _mm512_ternarylogic_epi32(_mm512_maskz_mov_epi8(low, one),
                                     _mm512_maskz_mov_epi8((low >> 1) | (high << 63), two),
                                     _mm512_maskz_mov_epi8((low >> 2) | (high << 62), four), 0xfe);
}

/// Calls f(i) for each set bit i of `bits` with from <= i < to.
template <typename F>
inline void for_each_bit(const std::uint64_t* bits, int from, int to, F&& f) {
    for (int chunk = from >> 6; from < to; ++chunk) {
        std::uint64_t m = bits[chunk] & (~std::uint64_t{0} << (from & 63));
        const int end = std::min(to, (chunk + 1) * 64);
        if (end < (chunk + 1) * 64) m &= (std::uint64_t{1} << (end & 63)) - 1;
        for (; m != 0; m &= m - 1) f(chunk * 64 + std::countr_zero(m));
        from = end;
    }
}

/// Fills the cube table for `grid`, in three layers of linear rows r (cells 64 r .. 64 r + 63):
/// T(r), the cells x, x+1, x+2 of row r as 3 bits (16-bit lanes); S(r) = T(r) | T(r+1) << 3 |
/// T(r+2) << 6, the 3x3 square in y; entry 64 r + x = S(r) | S(r+64) << 9 | S(r+128) << 18, the
/// cube. Each layer is formed once per row and reused by the three rows above it. Bitmaps of the
/// rows with a cell in each layer let the work skip empty rows: their cubes are zero, and
/// `dirty_rows` marks the table rows that are not, so a later grid clears only those.
ESF_TARGET_AVX512 void build_cubes(const VoxelGrid& grid, TraceScratch& scratch) {
    // Rows are counted from kCubeWordPad words before the grid, and each reads up to 131 words
    // ahead (zero past the grid's ends).
    constexpr int kWords = kCubeWordPad + kGridWords + kCubeWordPad;
    constexpr int kRows = kCubeWordPad + kGridWords;  // table rows
    constexpr int kChunks = kWords / 64 + 4;          // bitmap words, zero past the end
    constexpr int kRowChunks = (kRows + 63) / 64;
    constexpr int kRing = 256;  // S rows kept: 129 are read
    static_assert(kCubeWordPad >= 2 * kGridSide + 4 && kRing > 2 * kGridSide + 2);
    // Word `row` of the grid with kCubeWordPad zero words before it and after it.
    const auto word = [&grid](int row) {
        const int at = row - kCubeWordPad;
        return at >= 0 && at < kGridWords ? grid.words[static_cast<std::size_t>(at)]
                                          : std::uint64_t{0};
    };
    if (scratch.cubes.empty()) {
        scratch.cubes.assign(static_cast<std::size_t>(kCubePad + kGridCells), 0u);
        scratch.dirty_rows.assign(kRowChunks, 0);
    }
    // Rows with a cell: in the grid (any), in T (t_any), in S (s_any).
    std::array<std::uint64_t, kChunks> any{}, t_any{}, s_any{};
    constexpr int kPadChunks = kCubeWordPad / 64, kPadBits = kCubeWordPad % 64;
    static_assert(kPadBits > 0 && kGridWords % 64 == 0);
    for (int w = 0; w < kGridWords; w += 64) {
        std::uint64_t bits = 0;
        for (int j = 0; j < 64; j += 8) {
            const __m512i v = _mm512_loadu_si512(&grid.words[static_cast<std::size_t>(w + j)]);
            bits |= std::uint64_t{_mm512_test_epi64_mask(v, v)} << j;
        }
        const auto c = static_cast<std::size_t>(w / 64 + kPadChunks);
        any[c] |= bits << kPadBits;
        any[c + 1] |= bits >> (64 - kPadBits);
    }
    // Row r + k of a bitmap, for rows r of chunk c (k < 64).
    const auto ahead = [](const std::array<std::uint64_t, kChunks>& bits, std::size_t c, int k) {
        return k == 0 ? bits[c] : (bits[c] >> k) | (bits[c + 1] << (64 - k));
    };
    for (std::size_t c = 0; c + 1 < kChunks; ++c) t_any[c] = any[c] | ahead(any, c, 1);
    for (std::size_t c = 0; c + 1 < kChunks; ++c)
        s_any[c] = t_any[c] | ahead(t_any, c, 1) | ahead(t_any, c, 2);
    const auto has = [](const std::array<std::uint64_t, kChunks>& bits, int row) {
        return (bits[static_cast<std::size_t>(row >> 6)] >> (row & 63) & 1) != 0;
    };

    alignas(64) std::uint16_t t_rows[4][64];
    alignas(64) std::uint16_t s_rows[kRing][64];
    int t_next = 0, s_next = 0;  // the rows of T and S not formed yet start here
    const auto form_t = [&](int upto) ESF_TARGET_AVX512 {  // T of the rows < upto
        for_each_bit(t_any.data(), t_next, upto, [&](int row) ESF_TARGET_AVX512 {
            const __m512i bytes = cell_triples(word(row), word(row + 1));
            std::uint16_t* out = t_rows[row & 3];
            _mm512_store_si512(out, _mm512_cvtepu8_epi16(_mm512_castsi512_si256(bytes)));
            _mm512_store_si512(out + 32, _mm512_cvtepu8_epi16(_mm512_extracti64x4_epi64(bytes, 1)));
        });
        t_next = std::max(t_next, upto);
    };
    const auto t_half = [&](int row, int h) ESF_TARGET_AVX512 {
        return has(t_any, row) ? _mm512_load_si512(t_rows[row & 3] + h) : _mm512_setzero_si512();
    };
    const auto form_s = [&](int upto) ESF_TARGET_AVX512 {  // S of the rows < upto
        for_each_bit(s_any.data(), s_next, upto, [&](int row) ESF_TARGET_AVX512 {
            form_t(row + 3);
            for (int h = 0; h < 64; h += 32)
                _mm512_store_si512(s_rows[row & (kRing - 1)] + h,
                                   _mm512_ternarylogic_epi32(
                                       t_half(row, h), _mm512_slli_epi16(t_half(row + 1, h), 3),
                                       _mm512_slli_epi16(t_half(row + 2, h), 6), 0xfe));
        });
        s_next = std::max(s_next, upto);
    };
    const auto s_part = [&](int row, int j) ESF_TARGET_AVX512 {  // entries 16 j .. 16 j + 15
        return has(s_any, row)
                   ? _mm512_cvtepu16_epi32(_mm256_load_si256(
                         reinterpret_cast<const __m256i*>(s_rows[row & (kRing - 1)] + 16 * j)))
                   : _mm512_setzero_si512();
    };
    const auto table_row = [&](int row) ESF_TARGET_AVX512 {
        return reinterpret_cast<__m512i*>(scratch.cubes.data() + 64 * std::ptrdiff_t{row});
    };
    for (int c = 0; c < kRowChunks; ++c) {
        const auto uc = static_cast<std::size_t>(c);
        std::uint64_t live = s_any[uc] | s_any[uc + 1] | s_any[uc + 2];
        if (64 * (c + 1) > kRows) live &= (std::uint64_t{1} << (kRows & 63)) - 1;
        for (std::uint64_t m = scratch.dirty_rows[uc] & ~live; m != 0; m &= m - 1) {
            __m512i* entries = table_row(64 * c + std::countr_zero(m));
            for (int j = 0; j < 4; ++j) _mm512_storeu_si512(entries + j, _mm512_setzero_si512());
        }
        scratch.dirty_rows[uc] = live;
        for (; live != 0; live &= live - 1) {
            const int row = 64 * c + std::countr_zero(live);
            form_s(row + 2 * kGridSide + 1);
            __m512i* entries = table_row(row);
            for (int j = 0; j < 4; ++j)
                _mm512_storeu_si512(
                    entries + j,
                    _mm512_ternarylogic_epi32(
                        s_part(row, j), _mm512_slli_epi32(s_part(row + kGridSide, j), 9),
                        _mm512_slli_epi32(s_part(row + 2 * kGridSide, j), 18), 0xfe));
        }
    }
}

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
