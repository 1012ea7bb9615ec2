#pragma once
// Internal: the line tracers of each instruction set (esf_trace.cpp: the portable one and the
// choice; esf_trace_avx2.cpp; esf_trace_avx512.cpp), and what they share.
//
// The SIMD kernels trace 16 (AVX-512) or 8 (AVX2) lines of equal or similar length at once,
// one line per lane, three cells per look-up in a table of 3x3x3 cubes (esf_cube_table.hpp).
// The AVX-512 kernel's groups hold lines of one length (bucketed, see bucket_lines_avx512), so
// they run without per-lane masks. The AVX2 kernel's lines are sorted by length: a group runs
// min(n) cells without masks and only its few longer lanes run on with an activity mask.
// Gathers are never masked (slow on some CPUs): lanes past their end look up a cell inside the
// table and their bits are dropped.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "descriptors/esf/esf_trace.hpp"

namespace esf::detail {

/// The tracers, narrowest first; the AVX-512 one comes in two builds, counting cells with
/// VPOPCNTDQ or without.
enum class Tracer { kPortable, kAvx2, kAvx512, kAvx512Popcount };

/// The widest tracer this CPU runs.
Tracer widest_tracer();

// A line record of the SIMD kernels: two 32-bit words, each a cell and 14 bits of the line's
// number, low = start | (line mod 2^14) << 18 and high = end | (line >> 14) << 18. A vector of
// records splits into its starts and ends by one permutation each (no narrowing of 64-bit
// lanes), and the line numbers follow by shifts.
inline constexpr unsigned kCellBits = 3 * kGridBits;
inline constexpr unsigned kLinePartBits = 32 - kCellBits;
inline constexpr std::uint32_t kCellMask = (std::uint32_t{1} << kCellBits) - 1;
inline constexpr std::uint32_t kLinePartMask = (std::uint32_t{1} << kLinePartBits) - 1;
inline constexpr std::size_t kMaxPackedLines = std::size_t{1} << (2 * kLinePartBits);

/// The record of line `line` (< kMaxPackedLines) from `start` to `end`.
inline std::uint64_t line_record(std::uint32_t start, std::uint32_t end, std::size_t line) {
    const std::uint32_t low = start | static_cast<std::uint32_t>(line & kLinePartMask) << kCellBits;
    const std::uint32_t high = end | static_cast<std::uint32_t>(line >> kLinePartBits) << kCellBits;
    return low | std::uint64_t{high} << 32;
}

/// Lines per chunk of LineChunker: a multiple of the 16 lanes of a group.
inline constexpr std::uint32_t kChunkLines = 256;

/// Lines the SIMD kernels form records for at a time before they bucket them: the records of a
/// block stay in the L1 cache between the vector pass that forms them and the bucketing.
inline constexpr std::size_t kRecordBlockLines = 1024;

/// Buckets line records by visited count, a block of lines at a time: each count fills chunks
/// of kChunkLines records taken in turn from one pool (scratch.chunked), so every group of lanes
/// in a chunk has lines of one length. Chunks are numbered in the order they are opened; each
/// count's last chunk may be partly filled (scratch.chunk_size). Unlike a counting sort, no
/// tally of the counts is needed first.
class LineChunker {
  public:
    /// Room for `lines` lines in all.
    LineChunker(std::size_t lines, TraceScratch& scratch);

    /// Adds `count` lines: their visited counts and records.
    void add(const std::uint8_t* visited, const std::uint64_t* records, std::size_t count) {
        std::uint64_t* const pool = pool_;
        const auto place = [&](std::uint32_t v, std::uint64_t record) {
            std::uint32_t at = next_[v];
            if (at % kChunkLines == 0) [[unlikely]] {  // one record in kChunkLines
                chunk_visited_[chunks_] = static_cast<std::uint8_t>(v);
                at = chunks_++ * kChunkLines;
            }
            pool[at] = record;
            next_[v] = at + 1;
        };
        // Eight lines a round, their counts by one load (the loop is bound by its instructions).
        std::size_t i = 0;
        for (; i + 8 <= count; i += 8) {
            std::uint64_t eight;
            std::memcpy(&eight, visited + i, sizeof eight);
            for (unsigned l = 0; l < 8; ++l) place((eight >> (8 * l)) & 255, records[i + l]);
        }
        for (; i < count; ++i) place(visited[i], records[i]);
    }

    /// Sets every chunk's size; returns the number of chunks.
    std::size_t finish();

  private:
    TraceScratch& scratch_;
    std::uint64_t* pool_;
    std::uint8_t* chunk_visited_;
    // Per count: where its next record goes (0: no chunk yet). A count whose next place starts
    // a chunk has filled its chunk (or has none) and opens the next free one.
    std::array<std::uint32_t, kGridSide + 1> next_{};
    std::uint32_t chunks_ = 0;
};

/// trace_lines() with AVX-512, for fewer than kMaxPackedLines lines. `skip_known`: the lines
/// meet LineEnds::kSetBeforeDilation; `with_popcount`: the build that counts with VPOPCNTDQ
/// (needs avx512_vpopcntdq_available()).
void trace_lines_avx512(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                        std::span<const std::uint32_t> ends, std::span<std::uint32_t> occupied,
                        std::span<std::uint8_t> visited, TraceScratch& scratch, bool skip_known,
                        bool with_popcount);

/// trace_lines() with AVX2, for fewer than kMaxPackedLines lines. `skip_known`: as for
/// trace_lines_avx512().
void trace_lines_avx2(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                      std::span<const std::uint32_t> ends, std::span<std::uint32_t> occupied,
                      std::span<std::uint8_t> visited, TraceScratch& scratch, bool skip_known);

}  // namespace esf::detail
