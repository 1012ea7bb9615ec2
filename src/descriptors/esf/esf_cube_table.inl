// Internal: builds the table of 3x3x3 cubes of esf_cube_table.hpp that the SIMD line tracers look
// cells up in, three at a time. Included once per instruction set, in the including
// file's namespace, with ESF_CUBE_TABLE_TARGET set to its target attribute; the file defines with
// that target, before the inclusion, the row kernels:
//   std::uint64_t words_with_cells(const std::uint64_t* words)   bit j: words[j] != 0 (j < 64)
//   void form_triples(std::uint64_t low, std::uint64_t high, std::uint16_t* row)
//       entry x (< 64): the cells x, x+1, x+2 of the word `low`, continued into `high`, as 3 bits
//   void form_squares(const std::uint16_t* t0, const std::uint16_t* t1, const std::uint16_t* t2,
//                     std::uint16_t* row)      entry x: t0[x] | t1[x] << 3 | t2[x] << 6
//   void form_cubes(const std::uint16_t* s0, const std::uint16_t* s1, const std::uint16_t* s2,
//                   std::uint32_t* entries)    entry x: s0[x] | s1[x] << 9 | s2[x] << 18
//   void clear_cubes(std::uint32_t* entries)   64 entries set to 0
// Rows of 64 uint16 are 64-byte aligned; `entries` need not be. No include guard.

/// Fills the cube table for `grid`, in three layers of linear rows r (cells 64 r .. 64 r + 63):
/// T(r), the cells x, x+1, x+2 of row r as 3 bits; S(r) = T(r) | T(r+1) << 3 | T(r+2) << 6, the
/// 3x3 square in y; entry 64 r + x = S(r) | S(r+64) << 9 | S(r+128) << 18, the cube. Each layer
/// is formed once per row and reused by the three rows above it. Bitmaps of the rows with a cell
/// in each layer let the work skip empty rows: their cubes are zero, and `dirty_rows` marks the
/// table rows that are not, so a later grid clears only those (whichever tracer built them).
ESF_CUBE_TABLE_TARGET void build_cubes(const VoxelGrid& grid, TraceScratch& scratch) {
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
        const std::uint64_t bits = words_with_cells(&grid.words[static_cast<std::size_t>(w)]);
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

    alignas(64) static constexpr std::uint16_t kEmptyRow[64] = {};
    alignas(64) std::uint16_t t_rows[4][64];
    alignas(64) std::uint16_t s_rows[kRing][64];
    int t_next = 0, s_next = 0;  // the rows of T and S not formed yet start here
    const auto form_t = [&](int upto) ESF_CUBE_TABLE_TARGET {  // T of the rows < upto
        for_each_bit(t_any.data(), t_next, upto, [&](int row) ESF_CUBE_TABLE_TARGET {
            form_triples(word(row), word(row + 1), t_rows[row & 3]);
        });
        t_next = std::max(t_next, upto);
    };
    const auto t_row = [&](int row) -> const std::uint16_t* {
        return has(t_any, row) ? t_rows[row & 3] : kEmptyRow;
    };
    const auto form_s = [&](int upto) ESF_CUBE_TABLE_TARGET {  // S of the rows < upto
        for_each_bit(s_any.data(), s_next, upto, [&](int row) ESF_CUBE_TABLE_TARGET {
            form_t(row + 3);
            form_squares(t_row(row), t_row(row + 1), t_row(row + 2), s_rows[row & (kRing - 1)]);
        });
        s_next = std::max(s_next, upto);
    };
    const auto s_row = [&](int row) -> const std::uint16_t* {
        return has(s_any, row) ? s_rows[row & (kRing - 1)] : kEmptyRow;
    };
    const auto table_row = [&](int row) { return scratch.cubes.data() + 64 * std::ptrdiff_t{row}; };
    for (int c = 0; c < kRowChunks; ++c) {
        const auto uc = static_cast<std::size_t>(c);
        std::uint64_t live = s_any[uc] | s_any[uc + 1] | s_any[uc + 2];
        if (64 * (c + 1) > kRows) live &= (std::uint64_t{1} << (kRows & 63)) - 1;
        for (std::uint64_t m = scratch.dirty_rows[uc] & ~live; m != 0; m &= m - 1)
            clear_cubes(table_row(64 * c + std::countr_zero(m)));
        scratch.dirty_rows[uc] = live;
        for (; live != 0; live &= live - 1) {
            const int row = 64 * c + std::countr_zero(live);
            form_s(row + 2 * kGridSide + 1);
            form_cubes(s_row(row), s_row(row + kGridSide), s_row(row + 2 * kGridSide),
                       table_row(row));
        }
    }
}
