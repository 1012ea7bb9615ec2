#pragma once
// Internal: the 3-D Bresenham line tracer of the ESF descriptor, over the voxel grid
// (esf_voxel_grid.hpp). A line is traced from its start cell towards its end cell exactly as
// pcl::ESFEstimation::lci does: max(L, 1) cells are visited, L = the largest axis difference,
// the start cell is counted and the end cell is not.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "descriptors/esf/esf_voxel_grid.hpp"
#include "esf/core/kernels.hpp"

namespace esf::detail {

/// Number of cells a line between two cells visits: max(L, 1).
inline std::uint32_t visited_cells(std::uint32_t start, std::uint32_t end) {
    const auto axis = [&](int shift) {
        const int a = static_cast<int>((start >> shift) & 63);
        const int b = static_cast<int>((end >> shift) & 63);
        return a > b ? a - b : b - a;
    };
    int length = axis(0);
    length = axis(6) > length ? axis(6) : length;
    length = axis(12) > length ? axis(12) : length;
    return length > 0 ? static_cast<std::uint32_t>(length) : 1u;
}

/// Scratch buffers of trace_lines(), kept between calls to avoid allocation.
struct TraceScratch {
    // SIMD kernels: a block of lines packed, in input order, then all lines in chunks of lines
    // of one visited count (see LineChunker)
    std::vector<std::uint64_t> records, chunked;
    std::vector<std::uint8_t> chunk_visited;  // per chunk: the visited count of its lines
    std::vector<std::uint32_t> chunk_size;    // per chunk: how many lines it holds
    std::vector<std::uint32_t> cubes;         // 3x3x3 cube occupancy per cell (SIMD kernels)
    std::vector<std::uint64_t> dirty_rows;    // bitmap: rows of `cubes` that are not all zero
};

/// What trace_lines() may assume about its lines.
enum class LineEnds {
    kAny,
    /// Every start and end cell is a cell that was set before grid.dilate(): the start, its
    /// successor and the end's predecessor then lie in the dilated grid, and are not looked up.
    kSetBeforeDilation,
};

/// For every line i (starts[i] -> ends[i]): occupied[i] = occupied cells on it, visited[i] =
/// cells visited. `kernels`: the widest tracer the CPU has (kBest: AVX-512 counting cells with
/// VPOPCNTDQ where present), or at most a narrower one (kAvx512: AVX-512 without VPOPCNTDQ, as
/// on Skylake-SP; kAvx2; kPortable); all give identical counts.
void trace_lines(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                 std::span<const std::uint32_t> ends, std::span<std::uint32_t> occupied,
                 std::span<std::uint8_t> visited, TraceScratch& scratch,
                 Kernels kernels = Kernels::kBest, LineEnds line_ends = LineEnds::kAny);

/// The portable kernel.
void trace_lines_scalar(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                        std::span<const std::uint32_t> ends, std::span<std::uint32_t> occupied,
                        std::span<std::uint8_t> visited);

/// Name of the widest tracer this CPU runs ("avx512-popcnt", "avx512", "avx2" or "portable").
const char* trace_kernel_name();

/// Picks the fastest tracing kernel on this CPU by timing the real work: an estimator's first
/// call runs the widest kernel untimed (it meets cold caches and first touches the working
/// memory), the next ones try each SIMD kernel the CPU supports in turn (up to kRounds rounds,
/// the widest first), and the one with the least time per visited cell (calls trace different
/// clouds) then traces every later call. A narrower kernel must beat the widest by kMargin: two
/// kernels within the noise of each other must not make the choice a coin toss. After each round, a
/// narrower kernel slower per cell than the widest's best by more than kDrop takes no further turns
/// (it cannot come within the margin, and each of its turns costs a slow call); once only the
/// widest is left, it is chosen. Gathers, on which the AVX-512 kernels lean, cost very differently
/// across CPUs, so the widest kernel need not be the fastest. Every kernel gives the same counts:
/// only the speed depends on the choice. Each estimator holds its own (no shared state).
class TraceKernelTrials {
  public:
    static constexpr int kRounds = 3;
    static constexpr double kMargin = 0.05;
    static constexpr double kDrop = 0.2;
    static constexpr int kWarmUpCalls = 1;

    TraceKernelTrials();
    /// Whether the choice is made (at once when the CPU offers one kernel).
    bool decided() const { return decided_; }
    /// The kernels for the next call: the next ones to try, or the choice.
    Kernels next() const;
    /// Records how long `kernels` (the value next() gave) took to visit `cells` cells.
    void record(Kernels kernels, double seconds, std::size_t cells);

  private:
    void end_round();

    std::vector<Kernels> candidates_;
    std::vector<double> best_;   // least time per cell so far, per candidate
    std::vector<bool> dropped_;  // per candidate: no further turns
    std::size_t turn_ = 0;       // the candidate whose turn it is
    int warm_up_left_ = kWarmUpCalls;
    int rounds_ = 0;  // rounds finished
    Kernels chosen_ = Kernels::kBest;
    bool decided_ = false;
};

}  // namespace esf::detail
