// Internal: the AVX-512 group loop of the ESF line tracer (see esf_trace_avx512.cpp), included once
// per instruction set variant with ESF_CUBE_TARGET (the target attribute) and ESF_CUBE_POPCNT (1:
// count the three looked-up cells with one VPOPCNTD; 0: with three mask tests).
// No include guard: esf_trace_avx512.cpp includes it twice, in two namespaces.

struct CubeLanes {
    __m512 start, major_step, step1, step2;  // anchor cell arithmetic, in float (exact: < 2^24)
    __m512 slope1, slope2, intercept;        // v(i) = i * slope + intercept
    __m512 slope1x3, slope2x3, major_step_x3;
    __m512 rise1, rise2;    // 1 - slope
    __m512 after1, after2;  // 1 - 2 slope
    __m512i first_bit, base1, major_weight, weight1, weight2, occupied;
};

/// The value of the major axis, and of the first and second minor axis (x-major: y, z;
/// y-major: x, z; z-major: x, y) of each lane.
struct AxisRoles {
    __mmask16 x_major, y_major, z_major;
};

ESF_CUBE_TARGET inline __m512i major_of(const AxisRoles& r, const __m512i* v) {
    return _mm512_mask_blend_epi32(r.x_major, _mm512_mask_blend_epi32(r.y_major, v[2], v[1]), v[0]);
}
ESF_CUBE_TARGET inline __m512i minor1_of(const AxisRoles& r, const __m512i* v) {
    return _mm512_mask_blend_epi32(r.x_major, v[0], v[1]);
}
ESF_CUBE_TARGET inline __m512i minor2_of(const AxisRoles& r, const __m512i* v) {
    return _mm512_mask_blend_epi32(r.z_major, v[2], v[1]);
}

/// `visited`: max(L, 1), the same for every line of the group.
ESF_CUBE_TARGET inline __attribute__((always_inline)) CubeLanes setup_cubes(__m512i s, __m512i t,
                                                                            int visited,
                                                                            bool skip_known) {
    const __m512i zero = _mm512_setzero_si512(), one = _mm512_set1_epi32(1);
    const __m512i m63 = _mm512_set1_epi32(63);
    __m512i length[3], step[3], weight[3];  // weight: signed bit weight of the axis in a cube
    __m512i anchor_offset = zero, base0 = zero;
    for (int k = 0; k < 3; ++k) {
        const unsigned shift = static_cast<unsigned>(k * kGridBits);
        const __m512i d = _mm512_sub_epi32(_mm512_and_si512(_mm512_srli_epi32(t, shift), m63),
                                           _mm512_and_si512(_mm512_srli_epi32(s, shift), m63));
        length[k] = _mm512_abs_epi32(d);
        const __m512i unit = _mm512_set1_epi32(1 << shift);
        const __m512i w = _mm512_set1_epi32(k == 0 ? 1 : k == 1 ? 3 : 9);
        const __mmask16 down = _mm512_cmplt_epi32_mask(d, zero);
        step[k] = _mm512_mask_sub_epi32(unit, down, zero, unit);
        weight[k] = _mm512_mask_sub_epi32(w, down, zero, w);
        // Walking down an axis, cell i sits two steps above the cube's corner.
        anchor_offset =
            _mm512_mask_sub_epi32(anchor_offset, down, anchor_offset, _mm512_add_epi32(unit, unit));
        base0 = _mm512_mask_add_epi32(base0, down, base0, _mm512_add_epi32(w, w));
    }
    const __mmask16 x_major = _mm512_cmpge_epi32_mask(length[0], length[1]) &
                              _mm512_cmpge_epi32_mask(length[0], length[2]);
    const __mmask16 y_major =
        static_cast<__mmask16>(~x_major & _mm512_cmpge_epi32_mask(length[1], length[2]));
    const __mmask16 z_major = static_cast<__mmask16>(~(x_major | y_major));
    const AxisRoles roles{x_major, y_major, z_major};
    const __m512 l = _mm512_set1_ps(static_cast<float>(visited));
    const __m512 half_per_cell =
        _mm512_set1_ps(kHalfPerCell[static_cast<std::size_t>(visited - 1)]);
    CubeLanes lanes;
    lanes.start = _mm512_cvtepi32_ps(_mm512_add_epi32(s, anchor_offset));
    lanes.major_step = _mm512_cvtepi32_ps(major_of(roles, step));
    lanes.step1 = _mm512_cvtepi32_ps(minor1_of(roles, step));
    lanes.step2 = _mm512_cvtepi32_ps(minor2_of(roles, step));
    const __m512i a1 = minor1_of(roles, length), a2 = minor2_of(roles, length);
    lanes.slope1 = _mm512_mul_ps(_mm512_cvtepi32_ps(_mm512_add_epi32(a1, a1)), half_per_cell);
    lanes.slope2 = _mm512_mul_ps(_mm512_cvtepi32_ps(_mm512_add_epi32(a2, a2)), half_per_cell);
    lanes.intercept = _mm512_mul_ps(_mm512_sub_ps(l, _mm512_set1_ps(0.5f)), half_per_cell);
    lanes.rise1 = _mm512_sub_ps(_mm512_set1_ps(1.0f), lanes.slope1);
    lanes.rise2 = _mm512_sub_ps(_mm512_set1_ps(1.0f), lanes.slope2);
    const __m512 three = _mm512_set1_ps(3.0f);
    lanes.slope1x3 = _mm512_mul_ps(lanes.slope1, three);
    lanes.slope2x3 = _mm512_mul_ps(lanes.slope2, three);
    lanes.major_step_x3 = _mm512_mul_ps(lanes.major_step, three);
    lanes.after1 = _mm512_sub_ps(lanes.rise1, lanes.slope1);
    lanes.after2 = _mm512_sub_ps(lanes.rise2, lanes.slope2);
    lanes.major_weight = major_of(roles, weight);
    lanes.first_bit = _mm512_sllv_epi32(one, base0);
    lanes.base1 = _mm512_add_epi32(base0, lanes.major_weight);
    lanes.weight1 = minor1_of(roles, weight);
    lanes.weight2 = minor2_of(roles, weight);
    // With known ends, cells 0, 1 and L-1 count without a look-up and the walk covers 2..L-2.
    lanes.occupied = _mm512_set1_epi32(skip_known ? std::min(visited, 3) : 0);
    return lanes;
}

/// How many of the cells i, i+1 and i+2 trace_triple() counts in every lane: all three, or the
/// first one or two (at the end of a group: all its lines have one length).
enum CellsCounted { kFirstCell = 1, kFirstTwoCells = 2, kAllCells = 3 };

/// Where a walk is at cell i: v(i) of both minor axes and the anchor cell arithmetic of the
/// major axis (start + i * major_step). Each step of 3 cells adds 3 slope and 3 major_step: the
/// sums' rounding (under 1e-4 after 64 cells) stays far inside the margin of 1/(4L) of v(i).
struct CubeWalk {
    __m512 v1, v2, major;
};

ESF_CUBE_TARGET inline CubeWalk start_walk(const CubeLanes& lanes, int first_cell) {
    const __m512 fi = _mm512_set1_ps(static_cast<float>(first_cell));
    return {_mm512_fmadd_ps(fi, lanes.slope1, lanes.intercept),
            _mm512_fmadd_ps(fi, lanes.slope2, lanes.intercept),
            _mm512_fmadd_ps(fi, lanes.major_step, lanes.start)};
}

ESF_CUBE_TARGET inline void advance_walk(const CubeLanes& lanes, CubeWalk& walk) {
    walk.v1 = _mm512_add_ps(walk.v1, lanes.slope1x3);
    walk.v2 = _mm512_add_ps(walk.v2, lanes.slope2x3);
    walk.major = _mm512_add_ps(walk.major, lanes.major_step_x3);
}

/// Cells i, i+1 and i+2 of every lane (the walk at cell i), as many as `counted` says.
template <CellsCounted counted>
ESF_CUBE_TARGET inline void trace_triple(CubeLanes& lanes, const int* cubes, const CubeWalk& walk) {
    constexpr int kFloor = _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC;
    const __m512 v1 = walk.v1, v2 = walk.v2;
    const __m512 q1 = _mm512_roundscale_ps(v1, kFloor);
    const __m512 q2 = _mm512_roundscale_ps(v2, kFloor);
    const __m512 r1 = _mm512_sub_ps(v1, q1), r2 = _mm512_sub_ps(v2, q2);
    const __mmask16 next1 = _mm512_cmp_ps_mask(r1, lanes.rise1, _CMP_GE_OQ);
    const __mmask16 next2 = _mm512_cmp_ps_mask(r2, lanes.rise2, _CMP_GE_OQ);
    // The step from cell i+1 to i+2: r + 2 slope >= 1 + next (one compare, no floor).
    const __m512 one_f = _mm512_set1_ps(1.0f);
    const __mmask16 later1 = _mm512_cmp_ps_mask(
        r1, _mm512_mask_add_ps(lanes.after1, next1, lanes.after1, one_f), _CMP_GE_OQ);
    const __mmask16 later2 = _mm512_cmp_ps_mask(
        r2, _mm512_mask_add_ps(lanes.after2, next2, lanes.after2, one_f), _CMP_GE_OQ);
    const __m512 position =
        _mm512_fmadd_ps(q2, lanes.step2, _mm512_fmadd_ps(q1, lanes.step1, walk.major));
    const __m512i anchor = _mm512_cvttps_epi32(position);
    const __m512i cube = _mm512_mask_i32gather_epi32(
        _mm512_setzero_si512(), static_cast<__mmask16>(0xffff), anchor, cubes, 4);
    __m512i bit1 = _mm512_mask_add_epi32(lanes.base1, next1, lanes.base1, lanes.weight1);
    bit1 = _mm512_mask_add_epi32(bit1, next2, bit1, lanes.weight2);
    __m512i bit2 = _mm512_add_epi32(bit1, lanes.major_weight);
    bit2 = _mm512_mask_add_epi32(bit2, later1, bit2, lanes.weight1);
    bit2 = _mm512_mask_add_epi32(bit2, later2, bit2, lanes.weight2);
    const __m512i one = _mm512_set1_epi32(1);
    __mmask16 live[3] = {0xffff, 0xffff, 0xffff};  // cells i, i+1, i+2 before the lines' end
    if (counted == kFirstCell || counted == kFirstTwoCells) live[2] = 0;
    if (counted == kFirstCell) live[1] = 0;
#if ESF_CUBE_POPCNT
    // One population count of the three selected bits.
    const __m512i first = _mm512_maskz_mov_epi32(live[0], lanes.first_bit);
    const __m512i second = _mm512_maskz_sllv_epi32(live[1], one, bit1);
    const __m512i third = _mm512_maskz_sllv_epi32(live[2], one, bit2);
    const __m512i selected =
        _mm512_and_si512(cube, _mm512_ternarylogic_epi32(first, second, third, 0xfe));
    lanes.occupied = _mm512_add_epi32(lanes.occupied, _mm512_popcnt_epi32(selected));
#else
    const __mmask16 first = live[0] & _mm512_test_epi32_mask(cube, lanes.first_bit);
    const __mmask16 second = live[1] & _mm512_test_epi32_mask(cube, _mm512_sllv_epi32(one, bit1));
    const __mmask16 third = live[2] & _mm512_test_epi32_mask(cube, _mm512_sllv_epi32(one, bit2));
    lanes.occupied = _mm512_mask_add_epi32(lanes.occupied, first, lanes.occupied, one);
    lanes.occupied = _mm512_mask_add_epi32(lanes.occupied, second, lanes.occupied, one);
    lanes.occupied = _mm512_mask_add_epi32(lanes.occupied, third, lanes.occupied, one);
#endif
}

/// Starts, ends and line numbers of the `live` records from `record` (line_record()).
ESF_CUBE_TARGET inline void unpack_lines(const std::uint64_t* record, __mmask16 live,
                                         __m512i& starts, __m512i& ends, __m512i& lines) {
    const __m512i first = _mm512_maskz_loadu_epi64(static_cast<__mmask8>(live), record);
    const __m512i last = _mm512_maskz_loadu_epi64(static_cast<__mmask8>(live >> 8), record + 8);
    const __m512i even =
        _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
    const __m512i low = _mm512_permutex2var_epi32(first, even, last);
    const __m512i high =
        _mm512_permutex2var_epi32(first, _mm512_add_epi32(even, _mm512_set1_epi32(1)), last);
    const __m512i cell = _mm512_set1_epi32(static_cast<int>(kCellMask));
    starts = _mm512_and_si512(low, cell);
    ends = _mm512_and_si512(high, cell);
    lines = _mm512_or_si512(_mm512_srli_epi32(low, kCellBits),
                            _mm512_slli_epi32(_mm512_srli_epi32(high, kCellBits), kLinePartBits));
}

/// Traces the chunked lines of bucket_lines_avx512() through the cube table, 16 lines per
/// group: every line of a chunk visits the same number of cells.
ESF_CUBE_TARGET void trace_groups(const std::uint32_t* cube_table, const TraceScratch& scratch,
                                  std::size_t chunks, std::uint32_t* occupied, bool skip_known) {
    const auto* cubes = reinterpret_cast<const int*>(cube_table);
    const int first_cell = skip_known ? 2 : 0, end_skip = skip_known ? 1 : 0;
    for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
        const std::size_t count = scratch.chunk_size[chunk];
        const std::uint64_t* const records = scratch.chunked.data() + chunk * kChunkLines;
        const int chunk_cells = scratch.chunk_visited[chunk];
        const int cells = chunk_cells - end_skip;
        std::size_t group = 0;
        // Two full groups at a time: twice the independent work between look-ups. (Written out:
        // the same walk over an array of groups, one template for both loops, kept the lanes in
        // memory and took 7 % longer.)
        for (; group + 32 <= count; group += 32) {
            __m512i s, t, lines_a, lines_b;
            unpack_lines(records + group, 0xffff, s, t, lines_a);
            CubeLanes a = setup_cubes(s, t, chunk_cells, skip_known);
            unpack_lines(records + group + 16, 0xffff, s, t, lines_b);
            CubeLanes b = setup_cubes(s, t, chunk_cells, skip_known);
            int i = first_cell;
            CubeWalk walk_a = start_walk(a, i), walk_b = start_walk(b, i);
            for (; i + 2 < cells; i += 3, advance_walk(a, walk_a), advance_walk(b, walk_b)) {
                trace_triple<kAllCells>(a, cubes, walk_a);
                trace_triple<kAllCells>(b, cubes, walk_b);
            }
            if (cells - i == 1) {
                trace_triple<kFirstCell>(a, cubes, walk_a);
                trace_triple<kFirstCell>(b, cubes, walk_b);
            }
            if (cells - i == 2) {
                trace_triple<kFirstTwoCells>(a, cubes, walk_a);
                trace_triple<kFirstTwoCells>(b, cubes, walk_b);
            }
            _mm512_mask_i32scatter_epi32(occupied, 0xffff, lines_a, a.occupied, 4);
            _mm512_mask_i32scatter_epi32(occupied, 0xffff, lines_b, b.occupied, 4);
        }
        for (; group < count; group += 16) {
            const std::size_t size = std::min<std::size_t>(16, count - group);
            const auto live = static_cast<__mmask16>((1u << size) - 1u);
            __m512i s, t, lines;
            unpack_lines(records + group, live, s, t, lines);
            CubeLanes lanes = setup_cubes(s, t, chunk_cells, skip_known);
            int i = first_cell;
            CubeWalk walk = start_walk(lanes, i);
            for (; i + 2 < cells; i += 3, advance_walk(lanes, walk))
                trace_triple<kAllCells>(lanes, cubes, walk);
            if (cells - i == 1) trace_triple<kFirstCell>(lanes, cubes, walk);
            if (cells - i == 2) trace_triple<kFirstTwoCells>(lanes, cubes, walk);
            _mm512_mask_i32scatter_epi32(occupied, live, lines, lanes.occupied, 4);
        }
    }
}
