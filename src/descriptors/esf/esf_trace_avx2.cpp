// The AVX2 line tracer (see esf_trace.hpp): 8 lines of one length at a time (bucketed by
// LineChunker), three cells per look-up in the table of 3x3x3 cubes (the closed form of
// esf_trace_avx512.cpp, in 8 lanes).

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>

#include "core/simd.hpp"
#include "descriptors/esf/esf_cube_table.hpp"
#include "descriptors/esf/esf_trace_kernels.hpp"

// Vectors passed between this file's internal functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace esf::detail {

namespace {

/// Visited counts of all lines and their records (line_record()), 8 at a time, bucketed by
/// visited count (LineChunker).
ESF_TARGET_AVX2 std::size_t bucket_lines_avx2(std::span<const std::uint32_t> starts,
                                              std::span<const std::uint32_t> ends,
                                              std::span<std::uint8_t> visited,
                                              TraceScratch& scratch) {
    const __m256i m63 = _mm256_set1_epi32(63), one = _mm256_set1_epi32(1);
    // Bytes 0, 4, 8, 12 of each 128-bit half to its low 4 bytes.
    const __m256i low_bytes =
        _mm256_setr_epi8(0, 4, 8, 12, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, 0, 4, 8, 12,
                         -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1);
    const std::size_t count = starts.size();
    // A block of lines at a time: every line's count and record, 8 at a time, then the block's
    // records into their chunks.
    LineChunker chunker(count, scratch);
    std::vector<std::uint64_t>& records = scratch.records;
    records.resize(kRecordBlockLines);
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const __m256i line_part = _mm256_set1_epi32(static_cast<int>(kLinePartMask));
    for (std::size_t first = 0; first < count; first += kRecordBlockLines) {
        const std::size_t last = std::min(count, first + kRecordBlockLines);
        std::size_t i = first;
        for (; i + 8 <= last; i += 8) {
            const __m256i s =
                _mm256_loadu_si256(reinterpret_cast<const __m256i*>(starts.data() + i));
            const __m256i t = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(ends.data() + i));
            __m256i longest = one;
            for (int shift = 0; shift < 3 * kGridBits; shift += kGridBits) {
                const __m256i d =
                    _mm256_sub_epi32(_mm256_and_si256(_mm256_srli_epi32(t, shift), m63),
                                     _mm256_and_si256(_mm256_srli_epi32(s, shift), m63));
                longest = _mm256_max_epi32(longest, _mm256_abs_epi32(d));
            }
            const __m256i packed = _mm256_shuffle_epi8(longest, low_bytes);
            const std::uint64_t bytes =
                static_cast<std::uint32_t>(_mm256_extract_epi32(packed, 0)) |
                std::uint64_t{static_cast<std::uint32_t>(_mm256_extract_epi32(packed, 4))} << 32;
            std::memcpy(visited.data() + i, &bytes, 8);
            const __m256i line = _mm256_add_epi32(lane, _mm256_set1_epi32(static_cast<int>(i)));
            const __m256i low =
                _mm256_or_si256(s, _mm256_slli_epi32(_mm256_and_si256(line, line_part), kCellBits));
            const __m256i high = _mm256_or_si256(
                t, _mm256_slli_epi32(_mm256_srli_epi32(line, kLinePartBits), kCellBits));
            // Records 0-1 and 4-5, 2-3 and 6-7 (within 128-bit halves), then in order.
            const __m256i pairs = _mm256_unpacklo_epi32(low, high);
            const __m256i next_pairs = _mm256_unpackhi_epi32(low, high);
            _mm256_storeu_si256(reinterpret_cast<__m256i*>(records.data() + (i - first)),
                                _mm256_permute2x128_si256(pairs, next_pairs, 0x20));
            _mm256_storeu_si256(reinterpret_cast<__m256i*>(records.data() + (i - first) + 4),
                                _mm256_permute2x128_si256(pairs, next_pairs, 0x31));
        }
        for (; i < last; ++i) {
            visited[i] = static_cast<std::uint8_t>(visited_cells(starts[i], ends[i]));
            records[i - first] = line_record(starts[i], ends[i], i);
        }
        chunker.add(visited.data() + first, records.data(), last - first);
    }
    return chunker.finish();
}

// The row kernels of the cube table (esf_cube_table.inl).

/// Bytes x (< 32) of `bits` as `value` where bit x is set, 0 elsewhere.
ESF_TARGET_AVX2 inline __m256i bit_bytes(std::uint32_t bits, char value) {
    const __m256i byte_of_bit = _mm256_setr_epi8(0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 2,
                                                 2, 2, 2, 2, 2, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3);
    const __m256i bit_of_byte = _mm256_set1_epi64x(static_cast<long long>(0x8040201008040201ull));
    const __m256i spread =
        _mm256_shuffle_epi8(_mm256_set1_epi32(static_cast<int>(bits)), byte_of_bit);
    const __m256i set = _mm256_cmpeq_epi8(_mm256_and_si256(spread, bit_of_byte), bit_of_byte);
    return _mm256_and_si256(set, _mm256_set1_epi8(value));
}
ESF_TARGET_AVX2 inline std::uint64_t words_with_cells(const std::uint64_t* words) {
    std::uint64_t bits = 0;
    for (int j = 0; j < 64; j += 4) {
        const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(words + j));
        const int empty =
            _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(v, _mm256_setzero_si256())));
        bits |= std::uint64_t{static_cast<std::uint32_t>(~empty & 15)} << j;
    }
    return bits;
}
ESF_TARGET_AVX2 inline void form_triples(std::uint64_t low, std::uint64_t high,
                                         std::uint16_t* row) {
    const std::uint64_t next = (low >> 1) | (high << 63), after = (low >> 2) | (high << 62);
    for (int half = 0; half < 2; ++half) {
        const int shift = 32 * half;
        const __m256i bytes = _mm256_or_si256(
            _mm256_or_si256(bit_bytes(static_cast<std::uint32_t>(low >> shift), 1),
                            bit_bytes(static_cast<std::uint32_t>(next >> shift), 2)),
            bit_bytes(static_cast<std::uint32_t>(after >> shift), 4));
        auto* out = reinterpret_cast<__m256i*>(row + 32 * half);
        _mm256_store_si256(out, _mm256_cvtepu8_epi16(_mm256_castsi256_si128(bytes)));
        _mm256_store_si256(out + 1, _mm256_cvtepu8_epi16(_mm256_extracti128_si256(bytes, 1)));
    }
}
ESF_TARGET_AVX2 inline void form_squares(const std::uint16_t* t0, const std::uint16_t* t1,
                                         const std::uint16_t* t2, std::uint16_t* row) {
    const auto load = [](const std::uint16_t* t, int h) ESF_TARGET_AVX2 {
        return _mm256_load_si256(reinterpret_cast<const __m256i*>(t + h));
    };
    for (int h = 0; h < 64; h += 16)
        _mm256_store_si256(
            reinterpret_cast<__m256i*>(row + h),
            _mm256_or_si256(_mm256_or_si256(load(t0, h), _mm256_slli_epi16(load(t1, h), 3)),
                            _mm256_slli_epi16(load(t2, h), 6)));
}
ESF_TARGET_AVX2 inline void form_cubes(const std::uint16_t* s0, const std::uint16_t* s1,
                                       const std::uint16_t* s2, std::uint32_t* entries) {
    const auto part = [](const std::uint16_t* s, int j) ESF_TARGET_AVX2 {
        return _mm256_cvtepu16_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(s + 8 * j)));
    };
    for (int j = 0; j < 8; ++j)
        _mm256_storeu_si256(
            reinterpret_cast<__m256i*>(entries + 8 * j),
            _mm256_or_si256(_mm256_or_si256(part(s0, j), _mm256_slli_epi32(part(s1, j), 9)),
                            _mm256_slli_epi32(part(s2, j), 18)));
}
ESF_TARGET_AVX2 inline void clear_cubes(std::uint32_t* entries) {
    for (int j = 0; j < 8; ++j)
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(entries + 8 * j), _mm256_setzero_si256());
}

#define ESF_CUBE_TABLE_TARGET ESF_TARGET_AVX2
#include "descriptors/esf/esf_cube_table.inl"
#undef ESF_CUBE_TABLE_TARGET

/// One group of 8 lines, set up for the closed form (esf_trace_avx512.cpp): the anchor cell
/// arithmetic and v(i) = i * slope + intercept of both minor axes, in float (exact: < 2^24).
struct CubeLanes {
    __m256 start, major_step, step1, step2;
    __m256 slope1, slope2, intercept;
    __m256 slope1x3, slope2x3, major_step_x3;
    __m256 rise1, rise2;    // 1 - slope
    __m256 after1, after2;  // 1 - 2 slope
    __m256i first_bit, base1, major_weight, weight1, weight2, occupied;
};

/// The value of the major axis, and of the first and second minor axis (x-major: y, z;
/// y-major: x, z; z-major: x, y) of each lane; the masks are all-ones lanes.
struct AxisRoles {
    __m256i x_major, y_major, z_major;
};

ESF_TARGET_AVX2 inline __m256i major_of(const AxisRoles& r, const __m256i* v) {
    return _mm256_blendv_epi8(_mm256_blendv_epi8(v[2], v[1], r.y_major), v[0], r.x_major);
}
ESF_TARGET_AVX2 inline __m256i minor1_of(const AxisRoles& r, const __m256i* v) {
    return _mm256_blendv_epi8(v[0], v[1], r.x_major);
}
ESF_TARGET_AVX2 inline __m256i minor2_of(const AxisRoles& r, const __m256i* v) {
    return _mm256_blendv_epi8(v[2], v[1], r.z_major);
}

/// `visited`: max(L, 1), the same for every line of the group.
ESF_TARGET_AVX2 CubeLanes setup_cubes(__m256i s, __m256i t, int visited, bool skip_known) {
    const __m256i zero = _mm256_setzero_si256(), one = _mm256_set1_epi32(1);
    const __m256i m63 = _mm256_set1_epi32(63), ones = _mm256_set1_epi32(-1);
    __m256i length[3], step[3], weight[3];  // weight: signed bit weight of the axis in a cube
    __m256i anchor_offset = zero, base0 = zero;
    for (int k = 0; k < 3; ++k) {
        const int shift = k * kGridBits;
        const __m256i d = _mm256_sub_epi32(_mm256_and_si256(_mm256_srli_epi32(t, shift), m63),
                                           _mm256_and_si256(_mm256_srli_epi32(s, shift), m63));
        length[k] = _mm256_abs_epi32(d);
        const __m256i unit = _mm256_set1_epi32(1 << shift);
        const __m256i w = _mm256_set1_epi32(k == 0 ? 1 : k == 1 ? 3 : 9);
        const __m256i down = _mm256_cmpgt_epi32(zero, d);
        step[k] = _mm256_sign_epi32(unit, _mm256_or_si256(d, one));
        weight[k] = _mm256_sign_epi32(w, _mm256_or_si256(d, one));
        // Walking down an axis, cell i sits two steps above the cube's corner.
        anchor_offset =
            _mm256_sub_epi32(anchor_offset, _mm256_and_si256(down, _mm256_add_epi32(unit, unit)));
        base0 = _mm256_add_epi32(base0, _mm256_and_si256(down, _mm256_add_epi32(w, w)));
    }
    // "a >= b" is "not (b > a)".
    const __m256i x_major =
        _mm256_andnot_si256(_mm256_or_si256(_mm256_cmpgt_epi32(length[1], length[0]),
                                            _mm256_cmpgt_epi32(length[2], length[0])),
                            ones);
    const __m256i y_major = _mm256_andnot_si256(
        _mm256_or_si256(x_major, _mm256_cmpgt_epi32(length[2], length[1])), ones);
    const __m256i z_major = _mm256_andnot_si256(_mm256_or_si256(x_major, y_major), ones);
    const AxisRoles roles{x_major, y_major, z_major};
    const __m256 l = _mm256_set1_ps(static_cast<float>(visited));
    const __m256 half_per_cell =
        _mm256_set1_ps(kHalfPerCell[static_cast<std::size_t>(visited - 1)]);
    CubeLanes lanes;
    lanes.start = _mm256_cvtepi32_ps(_mm256_add_epi32(s, anchor_offset));
    lanes.major_step = _mm256_cvtepi32_ps(major_of(roles, step));
    lanes.step1 = _mm256_cvtepi32_ps(minor1_of(roles, step));
    lanes.step2 = _mm256_cvtepi32_ps(minor2_of(roles, step));
    const __m256i a1 = minor1_of(roles, length), a2 = minor2_of(roles, length);
    lanes.slope1 = _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(a1, a1)), half_per_cell);
    lanes.slope2 = _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(a2, a2)), half_per_cell);
    lanes.intercept = _mm256_mul_ps(_mm256_sub_ps(l, _mm256_set1_ps(0.5f)), half_per_cell);
    const __m256 one_f = _mm256_set1_ps(1.0f), three = _mm256_set1_ps(3.0f);
    lanes.rise1 = _mm256_sub_ps(one_f, lanes.slope1);
    lanes.rise2 = _mm256_sub_ps(one_f, lanes.slope2);
    lanes.slope1x3 = _mm256_mul_ps(lanes.slope1, three);
    lanes.slope2x3 = _mm256_mul_ps(lanes.slope2, three);
    lanes.major_step_x3 = _mm256_mul_ps(lanes.major_step, three);
    lanes.after1 = _mm256_sub_ps(lanes.rise1, lanes.slope1);
    lanes.after2 = _mm256_sub_ps(lanes.rise2, lanes.slope2);
    lanes.major_weight = major_of(roles, weight);
    lanes.first_bit = _mm256_sllv_epi32(one, base0);
    lanes.base1 = _mm256_add_epi32(base0, lanes.major_weight);
    lanes.weight1 = minor1_of(roles, weight);
    lanes.weight2 = minor2_of(roles, weight);
    // With known ends, cells 0, 1 and L-1 count without a look-up and the walk covers 2..L-2.
    lanes.occupied = _mm256_set1_epi32(skip_known ? std::min(visited, 3) : 0);
    return lanes;
}

/// Where a walk is at cell i: v(i) of both minor axes and the anchor cell arithmetic of the
/// major axis (start + i * major_step).
struct CubeWalk {
    __m256 v1, v2, major;
};

ESF_TARGET_AVX2 inline CubeWalk start_walk(const CubeLanes& lanes, int first_cell) {
    const __m256 fi = _mm256_set1_ps(static_cast<float>(first_cell));
    return {_mm256_fmadd_ps(fi, lanes.slope1, lanes.intercept),
            _mm256_fmadd_ps(fi, lanes.slope2, lanes.intercept),
            _mm256_fmadd_ps(fi, lanes.major_step, lanes.start)};
}

ESF_TARGET_AVX2 inline void advance_walk(const CubeLanes& lanes, CubeWalk& walk) {
    walk.v1 = _mm256_add_ps(walk.v1, lanes.slope1x3);
    walk.v2 = _mm256_add_ps(walk.v2, lanes.slope2x3);
    walk.major = _mm256_add_ps(walk.major, lanes.major_step_x3);
}

/// How many of the cells i, i+1 and i+2 trace_triple() counts in every lane: all three, or the
/// first one or two (at the end of a group: all its lines have one length).
enum CellsCounted { kFirstCell = 1, kFirstTwoCells = 2, kAllCells = 3 };

/// Cells i, i+1 and i+2 of every lane (the walk at cell i), as many as `counted` says.
template <CellsCounted counted>
ESF_TARGET_AVX2 inline void trace_triple(CubeLanes& lanes, const int* cubes, const CubeWalk& walk) {
    constexpr int kFloor = _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC;
    const __m256 q1 = _mm256_round_ps(walk.v1, kFloor);
    const __m256 q2 = _mm256_round_ps(walk.v2, kFloor);
    const __m256 position =
        _mm256_fmadd_ps(q2, lanes.step2, _mm256_fmadd_ps(q1, lanes.step1, walk.major));
    const __m256i cube = _mm256_i32gather_epi32(cubes, _mm256_cvttps_epi32(position), 4);
    const __m256i zero = _mm256_setzero_si256(), one = _mm256_set1_epi32(1);
    // Cube entries hold 27 bits: a looked-up cell is occupied where its bit leaves a positive
    // value, a hit is -1, and the hits are subtracted.
    __m256i hits = _mm256_cmpgt_epi32(_mm256_and_si256(cube, lanes.first_bit), zero);
    if constexpr (counted >= kFirstTwoCells) {
        const __m256 r1 = _mm256_sub_ps(walk.v1, q1), r2 = _mm256_sub_ps(walk.v2, q2);
        const __m256 next1 = _mm256_cmp_ps(r1, lanes.rise1, _CMP_GE_OQ);
        const __m256 next2 = _mm256_cmp_ps(r2, lanes.rise2, _CMP_GE_OQ);
        const auto as_int = [](__m256 m) ESF_TARGET_AVX2 { return _mm256_castps_si256(m); };
        __m256i bit1 =
            _mm256_add_epi32(lanes.base1, _mm256_and_si256(as_int(next1), lanes.weight1));
        bit1 = _mm256_add_epi32(bit1, _mm256_and_si256(as_int(next2), lanes.weight2));
        hits = _mm256_add_epi32(
            hits, _mm256_cmpgt_epi32(_mm256_and_si256(cube, _mm256_sllv_epi32(one, bit1)), zero));
        if constexpr (counted == kAllCells) {
            // The step from cell i+1 to i+2: r + 2 slope >= 1 + next (one compare, no floor).
            const __m256 one_f = _mm256_set1_ps(1.0f);
            const __m256 later1 = _mm256_cmp_ps(
                r1, _mm256_add_ps(lanes.after1, _mm256_and_ps(next1, one_f)), _CMP_GE_OQ);
            const __m256 later2 = _mm256_cmp_ps(
                r2, _mm256_add_ps(lanes.after2, _mm256_and_ps(next2, one_f)), _CMP_GE_OQ);
            __m256i bit2 = _mm256_add_epi32(bit1, lanes.major_weight);
            bit2 = _mm256_add_epi32(bit2, _mm256_and_si256(as_int(later1), lanes.weight1));
            bit2 = _mm256_add_epi32(bit2, _mm256_and_si256(as_int(later2), lanes.weight2));
            hits = _mm256_add_epi32(
                hits,
                _mm256_cmpgt_epi32(_mm256_and_si256(cube, _mm256_sllv_epi32(one, bit2)), zero));
        }
    }
    lanes.occupied = _mm256_sub_epi32(lanes.occupied, hits);
}

/// Starts, ends and line numbers of the 8 records from `record` (`lanes` of them: the others
/// read as a line from cell 0 to cell 0, whose walk stays inside the table).
ESF_TARGET_AVX2 inline void unpack_lines(const std::uint64_t* record, std::size_t lanes,
                                         __m256i& starts, __m256i& ends, __m256i& lines) {
    __m256i low, high;
    if (lanes == 8) {
        low = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(record));
        high = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(record + 4));
    } else {
        const __m256i lane = _mm256_setr_epi64x(0, 1, 2, 3);
        const auto live = [&](long long first) ESF_TARGET_AVX2 {
            return _mm256_cmpgt_epi64(_mm256_set1_epi64x(static_cast<long long>(lanes) - first),
                                      lane);
        };
        const auto* at = reinterpret_cast<const long long*>(record);
        low = _mm256_maskload_epi64(at, live(0));
        high = _mm256_maskload_epi64(at + 4, live(4));
    }
    // The low words of the records, then their high words (line_record()).
    const __m256i split = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
    const __m256i first = _mm256_permutevar8x32_epi32(low, split);
    const __m256i last = _mm256_permutevar8x32_epi32(high, split);
    const __m256i low_words = _mm256_permute2x128_si256(first, last, 0x20);
    const __m256i high_words = _mm256_permute2x128_si256(first, last, 0x31);
    const __m256i cell = _mm256_set1_epi32(static_cast<int>(kCellMask));
    starts = _mm256_and_si256(low_words, cell);
    ends = _mm256_and_si256(high_words, cell);
    lines =
        _mm256_or_si256(_mm256_srli_epi32(low_words, kCellBits),
                        _mm256_slli_epi32(_mm256_srli_epi32(high_words, kCellBits), kLinePartBits));
}

}  // namespace

ESF_TARGET_AVX2 void trace_lines_avx2(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                                      std::span<const std::uint32_t> ends,
                                      std::span<std::uint32_t> occupied,
                                      std::span<std::uint8_t> visited, TraceScratch& scratch,
                                      bool skip_known) {
    const std::size_t chunks = bucket_lines_avx2(starts, ends, visited, scratch);
    build_cubes(grid, scratch);
    const auto* cubes = reinterpret_cast<const int*>(scratch.cubes.data() + kCubePad);
    const int first_cell = skip_known ? 2 : 0, end_skip = skip_known ? 1 : 0;
    alignas(32) std::uint32_t line[8], result[8];
    for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
        const std::size_t count = scratch.chunk_size[chunk];
        const std::uint64_t* const records = scratch.chunked.data() + chunk * kChunkLines;
        const int chunk_cells = scratch.chunk_visited[chunk];
        const int cells = chunk_cells - end_skip;
        for (std::size_t group = 0; group < count; group += 8) {
            const std::size_t lanes = std::min<std::size_t>(8, count - group);
            __m256i s, t, lines;
            unpack_lines(records + group, lanes, s, t, lines);
            CubeLanes cube_lanes = setup_cubes(s, t, chunk_cells, skip_known);
            int i = first_cell;
            CubeWalk walk = start_walk(cube_lanes, i);
            for (; i + 2 < cells; i += 3, advance_walk(cube_lanes, walk))
                trace_triple<kAllCells>(cube_lanes, cubes, walk);
            if (cells - i == 1) trace_triple<kFirstCell>(cube_lanes, cubes, walk);
            if (cells - i == 2) trace_triple<kFirstTwoCells>(cube_lanes, cubes, walk);
            _mm256_store_si256(reinterpret_cast<__m256i*>(line), lines);
            _mm256_store_si256(reinterpret_cast<__m256i*>(result), cube_lanes.occupied);
            for (std::size_t k = 0; k < lanes; ++k) occupied[line[k]] = result[k];
        }
    }
}

}  // namespace esf::detail
