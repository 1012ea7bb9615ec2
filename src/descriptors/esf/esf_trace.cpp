#include "descriptors/esf/esf_trace.hpp"

#include <immintrin.h>

#include "descriptors/esf/esf_simd.hpp"

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Vectors passed between this file's internal AVX-512 functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cstdlib>
#include <limits>

namespace esf::detail {

namespace {

void dilate_portable(VoxelGrid::Words& words, int side) {
    // The 3x3x3 box is separable: dilate along x (bits), then y (rows), then z (slices).
    const std::uint64_t x_mask = side >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << side) - 1;
    for (auto& word : words) word = (word | (word << 1) | (word >> 1)) & x_mask;
    VoxelGrid::Words src = words;
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

/// dilate_portable() on 8 words per step.
ESF_TARGET_AVX512 void dilate_avx512(VoxelGrid::Words& words, int side) {
    const __m512i x_mask =
        _mm512_set1_epi64(side >= 64 ? -1 : static_cast<long long>((std::uint64_t{1} << side) - 1));
    const __m512i lane_y = _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7);
    // Along x, in place.
    for (int r = 0; r < kGridWords; r += 8) {
        const __m512i w = _mm512_load_si512(&words[static_cast<std::size_t>(r)]);
        _mm512_store_si512(
            &words[static_cast<std::size_t>(r)],
            _mm512_and_si512(_mm512_or_si512(w, _mm512_or_si512(_mm512_slli_epi64(w, 1),
                                                                _mm512_srli_epi64(w, 1))),
                             x_mask));
    }
    // Along y, into `rows` (one zero row before and after each slice's neighbours).
    alignas(64) VoxelGrid::Words rows;
    const __m512i below_side = _mm512_set1_epi64(side);
    for (int z = 0; z < kGridSide; ++z) {
        const std::uint64_t* slice = &words[static_cast<std::size_t>(z * kGridSide)];
        for (int y = 0; y < kGridSide; y += 8) {
            const __m512i ys = _mm512_add_epi64(lane_y, _mm512_set1_epi64(y));
            const __mmask8 has_prev = _mm512_cmpgt_epi64_mask(ys, _mm512_setzero_si512());
            const __mmask8 has_next =
                _mm512_cmplt_epi64_mask(_mm512_add_epi64(ys, _mm512_set1_epi64(1)), below_side);
            const __mmask8 inside = _mm512_cmplt_epi64_mask(ys, below_side);
            const __m512i prev = _mm512_maskz_loadu_epi64(has_prev, slice + y - 1);
            const __m512i next = _mm512_maskz_loadu_epi64(has_next, slice + y + 1);
            const __m512i w = _mm512_load_si512(slice + y);
            _mm512_store_si512(
                &rows[static_cast<std::size_t>(z * kGridSide + y)],
                _mm512_maskz_mov_epi64(inside, _mm512_or_si512(w, _mm512_or_si512(prev, next))));
        }
    }
    // Along z, back into the grid.
    for (int z = 0; z < kGridSide; ++z) {
        const bool has_prev = z > 0, has_next = z + 1 < side, inside = z < side;
        for (int y = 0; y < kGridSide; y += 8) {
            const std::size_t r = static_cast<std::size_t>(z * kGridSide + y);
            __m512i w = _mm512_setzero_si512();
            if (inside) {
                w = _mm512_load_si512(&rows[r]);
                if (has_prev) w = _mm512_or_si512(w, _mm512_load_si512(&rows[r - kGridSide]));
                if (has_next) w = _mm512_or_si512(w, _mm512_load_si512(&rows[r + kGridSide]));
            }
            _mm512_store_si512(&words[r], w);
        }
    }
}

}  // namespace

void VoxelGrid::dilate(int side, bool simd) {
    if (simd && avx512_available())
        dilate_avx512(words, side);
    else
        dilate_portable(words, side);
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

inline std::uint32_t trace_one(const VoxelGrid& grid, std::uint32_t start, const Axes& line) {
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
    return occupied;
}

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

// A line record of the AVX-512 kernel: start | end << kEndShift | line << kLineShift.
constexpr unsigned kEndShift = 3 * kGridBits, kLineShift = 2 * kEndShift;
constexpr std::uint64_t kCellMask = (std::uint64_t{1} << kEndShift) - 1;
constexpr std::size_t kMaxPackedLines = std::size_t{1} << (64 - kLineShift);

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

// The SIMD kernels trace 16 (AVX-512) or 8 (AVX2) lines of equal or similar length at once,
// one line per lane. The AVX-512 kernel's groups hold lines of one length (bucketed, see
// bucket_lines_avx512), so they run without per-lane masks. The AVX2 kernel's lines are sorted
// by length: a group runs min(n) cells without masks and only its few longer lanes run on with
// an activity mask. Gathers are never masked (slow on some CPUs): lanes past their end keep
// their look-up inside the table and their bits are dropped.

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

#define ESF_TARGET_AVX512_POPCNT                                                  \
    __attribute__((                                                               \
        target("avx512f,avx512bw,avx512vl,avx512dq,avx512vpopcntdq,avx2,fma,bmi," \
               "bmi2")))

namespace popcnt {
#define ESF_CUBE_TARGET ESF_TARGET_AVX512_POPCNT
#define ESF_CUBE_POPCNT 1
#include "descriptors/esf/esf_trace_cubes.inl"
#undef ESF_CUBE_TARGET
#undef ESF_CUBE_POPCNT
}  // namespace popcnt

ESF_TARGET_AVX512 void trace_lines_avx512(const VoxelGrid& grid,
                                          std::span<const std::uint32_t> starts,
                                          std::span<const std::uint32_t> ends,
                                          std::span<std::uint32_t> occupied,
                                          std::span<std::uint8_t> visited, TraceScratch& scratch,
                                          bool skip_known, bool with_popcnt) {
    const std::size_t chunks = bucket_lines_avx512(starts, ends, visited, scratch);
    build_cubes(grid, scratch);
    const std::uint32_t* cubes = scratch.cubes.data() + kCubePad;
    if (with_popcnt)
        popcnt::trace_groups(cubes, scratch, chunks, occupied.data(), skip_known);
    else
        plain::trace_groups(cubes, scratch, chunks, occupied.data(), skip_known);
}

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

enum class Kernel { kScalar, kAvx2, kAvx512, kAvx512Popcnt };

Kernel best_kernel() {
    if (avx512_available()) {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx512vpopcntdq") ? Kernel::kAvx512Popcnt : Kernel::kAvx512;
    }
    if (avx2_available()) return Kernel::kAvx2;
    return Kernel::kScalar;
}

}  // namespace

void trace_lines_scalar(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                        std::span<const std::uint32_t> ends, std::span<std::uint32_t> occupied,
                        std::span<std::uint8_t> visited) {
    assert(starts.size() == ends.size() && occupied.size() == starts.size());
    for (std::size_t i = 0; i < starts.size(); ++i) {
        const Axes line = setup_line(starts[i], ends[i]);
        occupied[i] = trace_one(grid, starts[i], line);
        visited[i] = static_cast<std::uint8_t>(line.visited);
    }
}

void trace_lines(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                 std::span<const std::uint32_t> ends, std::span<std::uint32_t> occupied,
                 std::span<std::uint8_t> visited, TraceScratch& scratch, TraceKernel kernel,
                 LineEnds line_ends) {
    assert(starts.size() == ends.size() && occupied.size() == starts.size() &&
           visited.size() == starts.size());
    static const Kernel best = best_kernel();  // CPU features do not change while running
    Kernel use = best;
    if (kernel == TraceKernel::kScalar) use = Kernel::kScalar;
    if (kernel == TraceKernel::kAvx2 && best != Kernel::kScalar) use = Kernel::kAvx2;
    if (kernel == TraceKernel::kAvx512 && best == Kernel::kAvx512Popcnt) use = Kernel::kAvx512;
    // The AVX-512 kernels pack line numbers into 28 bits (ESF draws at most 3 * 10^7 lines).
    static_assert(kMaxPackedLines == std::size_t{1} << 28);
    if ((use == Kernel::kAvx512 || use == Kernel::kAvx512Popcnt) &&
        starts.size() >= kMaxPackedLines)
        use = Kernel::kAvx2;
    switch (use) {
        case Kernel::kAvx512Popcnt:
        case Kernel::kAvx512:
            trace_lines_avx512(grid, starts, ends, occupied, visited, scratch,
                               line_ends == LineEnds::kSetBeforeDilation,
                               use == Kernel::kAvx512Popcnt);
            break;
        case Kernel::kAvx2:
            trace_lines_avx2(grid, starts, ends, occupied, visited, scratch);
            break;
        case Kernel::kScalar:
            trace_lines_scalar(grid, starts, ends, occupied, visited);
            break;
    }
}

TraceKernelTrials::TraceKernelTrials() {
    candidates_.push_back(TraceKernel::kBest);  // the widest
    const Kernel widest = best_kernel();
    if (widest == Kernel::kAvx512Popcnt) candidates_.push_back(TraceKernel::kAvx512);
    if (widest == Kernel::kAvx512Popcnt || widest == Kernel::kAvx512)
        candidates_.push_back(TraceKernel::kAvx2);
    best_.assign(candidates_.size(), std::numeric_limits<double>::infinity());
    dropped_.assign(candidates_.size(), false);
    decided_ = candidates_.size() == 1;
}

TraceKernel TraceKernelTrials::next() const { return decided_ ? chosen_ : candidates_[turn_]; }

void TraceKernelTrials::record(TraceKernel kernel, double seconds, std::size_t cells) {
    if (decided_) return;
    if (warm_up_left_ > 0) {
        --warm_up_left_;
        return;
    }
    const auto k = static_cast<std::size_t>(
        std::find(candidates_.begin(), candidates_.end(), kernel) - candidates_.begin());
    if (k < best_.size())
        best_[k] =
            std::min(best_[k], seconds / static_cast<double>(std::max<std::size_t>(cells, 1)));
    // The next candidate still in the trials, or the end of the round.
    do {
        if (++turn_ == candidates_.size()) {
            end_round();
            return;
        }
    } while (dropped_[turn_]);
}

void TraceKernelTrials::end_round() {
    turn_ = 0;  // the widest is never dropped
    ++rounds_;
    bool others_left = false;
    for (std::size_t c = 1; c < candidates_.size(); ++c) {
        if (best_[c] > (1.0 + kDrop) * best_[0]) dropped_[c] = true;
        others_left = others_left || !dropped_[c];
    }
    if (rounds_ < kRounds && others_left) return;
    // The widest (candidate 0) unless another is faster by the margin.
    std::size_t choice = 0;
    for (std::size_t c = 1; c < best_.size(); ++c)
        if (!dropped_[c] && best_[c] < (1.0 - kMargin) * best_[0] && best_[c] < best_[choice])
            choice = c;
    chosen_ = candidates_[choice];
    decided_ = true;
}

const char* trace_kernel_name() {
    switch (best_kernel()) {
        case Kernel::kAvx512Popcnt:
            return "avx512-popcnt";
        case Kernel::kAvx512:
            return "avx512";
        case Kernel::kAvx2:
            return "avx2";
        default:
            return "scalar";
    }
}

}  // namespace esf::detail
