#include "descriptors/esf/esf_trace.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cstring>

#include "core/simd.hpp"
#include "descriptors/esf/esf_trace_kernels.hpp"

namespace esf::detail {

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

}  // namespace

LineChunker::LineChunker(std::size_t lines, TraceScratch& scratch) : scratch_(scratch) {
    // Every chunk is full but each count's last: at most lines / kChunkLines + kGridSide + 1.
    const std::size_t most_chunks = lines / kChunkLines + kGridSide + 1;
    scratch.chunked.resize(most_chunks * kChunkLines);
    scratch.chunk_visited.resize(most_chunks);
    scratch.chunk_size.resize(most_chunks);
    pool_ = scratch.chunked.data();
    chunk_visited_ = scratch.chunk_visited.data();
}

std::size_t LineChunker::finish() {
    for (std::uint32_t c = 0; c < chunks_; ++c) scratch_.chunk_size[c] = kChunkLines;
    for (const std::uint32_t at : next_)  // each count's last chunk, full or not
        if (at != 0) scratch_.chunk_size[(at - 1) / kChunkLines] = (at - 1) % kChunkLines + 1;
    return chunks_;
}

Tracer widest_tracer() {
    if (avx512_available())
        return avx512_vpopcntdq_available() ? Tracer::kAvx512Popcount : Tracer::kAvx512;
    return avx2_available() ? Tracer::kAvx2 : Tracer::kPortable;
}

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
                 std::span<std::uint8_t> visited, TraceScratch& scratch, Kernels kernels,
                 LineEnds line_ends) {
    assert(starts.size() == ends.size() && occupied.size() == starts.size() &&
           visited.size() == starts.size());
    static const Tracer widest = widest_tracer();  // CPU features do not change while running
    Tracer use = widest;                           // kBest
    if (kernels == Kernels::kAvx512) use = std::min(widest, Tracer::kAvx512);
    if (kernels == Kernels::kAvx2) use = std::min(widest, Tracer::kAvx2);
    if (kernels == Kernels::kPortable) use = Tracer::kPortable;
    // The SIMD kernels pack line numbers into 28 bits (ESF draws at most 3 * 10^7 lines).
    static_assert(kMaxPackedLines == std::size_t{1} << 28);
    if (use >= Tracer::kAvx2 && starts.size() >= kMaxPackedLines) use = Tracer::kPortable;
    switch (use) {
        case Tracer::kAvx512Popcount:
        case Tracer::kAvx512:
            trace_lines_avx512(grid, starts, ends, occupied, visited, scratch,
                               line_ends == LineEnds::kSetBeforeDilation,
                               use == Tracer::kAvx512Popcount);
            break;
        case Tracer::kAvx2:
            trace_lines_avx2(grid, starts, ends, occupied, visited, scratch,
                             line_ends == LineEnds::kSetBeforeDilation);
            break;
        case Tracer::kPortable:
            trace_lines_scalar(grid, starts, ends, occupied, visited);
            break;
    }
}

const char* trace_kernel_name() {
    switch (widest_tracer()) {
        case Tracer::kAvx512Popcount:
            return "avx512-popcnt";
        case Tracer::kAvx512:
            return "avx512";
        case Tracer::kAvx2:
            return "avx2";
        case Tracer::kPortable:
            break;
    }
    return "portable";
}

}  // namespace esf::detail
