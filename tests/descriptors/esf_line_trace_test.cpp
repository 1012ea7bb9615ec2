// The ESF descriptor's voxel grid and line tracer: dilation and Bresenham cells against the
// definition and hand-computed cells, every SIMD tracer against the scalar one, and the trials
// that pick the fastest tracer at run time.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "descriptors/esf/esf_points.hpp"
#include "descriptors/esf/esf_trace.hpp"

namespace {

using esf::detail::pack_cell;

/// The SIMD line tracers (kAvx512: the build without VPOPCNTD).
constexpr esf::Kernels kSimdKernels[] = {esf::Kernels::kBest, esf::Kernels::kAvx512,
                                         esf::Kernels::kAvx2};

// One cell set: the 3x3x3 block around it is occupied, clipped at the border.
TEST(VoxelGrid, DilationMarksTheTwentySixNeighbours) {
    esf::detail::VoxelGrid grid;
    grid.clear();
    grid.set(pack_cell(10, 10, 10));
    grid.set(pack_cell(0, 0, 63));  // a corner: 8 cells inside the grid
    grid.dilate(64);
    int count = 0;
    for (auto w : grid.words) count += __builtin_popcountll(w);
    EXPECT_EQ(count, 27 + 8);
    EXPECT_TRUE(grid.occupied(pack_cell(9, 11, 9)));
    EXPECT_TRUE(grid.occupied(pack_cell(11, 9, 11)));
    EXPECT_FALSE(grid.occupied(pack_cell(12, 10, 10)));
    EXPECT_TRUE(grid.occupied(pack_cell(1, 1, 62)));
    EXPECT_FALSE(grid.occupied(pack_cell(2, 0, 63)));
}

// Line (0,0,0) -> (5,2,0): L = 5, a_y = 2, error starts at 2*2 - 5 = -1. By hand the visited
// cells are (0,0,0) (1,0,0) (2,1,0) (3,1,0) (4,2,0); the end cell (5,2,0) is not counted.
TEST(LineTrace, FollowsHandComputedBresenhamCells) {
    esf::detail::VoxelGrid grid;
    grid.clear();
    for (auto c : {pack_cell(0, 0, 0), pack_cell(1, 0, 0), pack_cell(2, 1, 0), pack_cell(3, 1, 0),
                   pack_cell(4, 2, 0)})
        grid.set(c);
    grid.set(pack_cell(2, 0, 0));  // next to the line, not on it
    const std::uint32_t start[] = {pack_cell(0, 0, 0), pack_cell(5, 2, 0), pack_cell(7, 7, 7)};
    const std::uint32_t end[] = {pack_cell(5, 2, 0), pack_cell(5, 2, 0), pack_cell(7, 7, 7)};
    std::uint32_t occupied[3];
    std::uint8_t visited[3];
    for (auto kernel : {esf::Kernels::kBest, esf::Kernels::kAvx512, esf::Kernels::kAvx2,
                        esf::Kernels::kPortable}) {
        esf::detail::TraceScratch scratch;
        esf::detail::trace_lines(grid, start, end, occupied, visited, scratch, kernel);
        EXPECT_EQ(occupied[0], 5);
        EXPECT_EQ(visited[0], 5);
        EXPECT_EQ(occupied[1], 0);  // zero-length line: its own (empty) cell, once
        EXPECT_EQ(visited[1], 1);
        EXPECT_EQ(occupied[2], 0);
        EXPECT_EQ(visited[2], 1);
    }
}

TEST(LineTrace, SimdKernelsMatchScalarOnRandomLines) {
    std::mt19937 rng(5);
    std::uniform_int_distribution<std::uint32_t> coord(0, 63);
    esf::detail::VoxelGrid grid;
    grid.clear();
    for (int i = 0; i < 3000; ++i) grid.set(pack_cell(coord(rng), coord(rng), coord(rng)));
    grid.dilate(64);
    const std::size_t n = 10007;  // not a multiple of the lane count
    std::vector<std::uint32_t> starts(n), ends(n);
    for (std::size_t i = 0; i < n; ++i) {
        starts[i] = pack_cell(coord(rng), coord(rng), coord(rng));
        ends[i] = i % 7 == 0 ? starts[i] : pack_cell(coord(rng), coord(rng), coord(rng));
    }
    std::vector<std::uint32_t> expected(n), actual(n);
    std::vector<std::uint8_t> expected_visited(n), actual_visited(n);
    esf::detail::trace_lines_scalar(grid, starts, ends, expected, expected_visited);
    for (auto kernel : kSimdKernels) {
        esf::detail::TraceScratch scratch;
        esf::detail::trace_lines(grid, starts, ends, actual, actual_visited, scratch, kernel);
        EXPECT_EQ(actual, expected);
        EXPECT_EQ(actual_visited, expected_visited);
    }
    for (std::size_t i = 0; i < n; ++i)
        ASSERT_EQ(expected_visited[i], esf::detail::visited_cells(starts[i], ends[i]));
}

// Both dilation kernels against the definition, on random grids of every side ESF allows.
TEST(VoxelGrid, DilationKernelsMatchTheDefinition) {
    std::mt19937 rng(3);
    for (int side : {8, 30, 40, 62, 64}) {
        std::uniform_int_distribution<std::uint32_t> coord(0, static_cast<std::uint32_t>(side) - 1);
        esf::detail::VoxelGrid grid;
        grid.clear();
        for (int i = 0; i < 150; ++i) grid.set(pack_cell(coord(rng), coord(rng), coord(rng)));
        grid.set(pack_cell(0, 0, 0));
        grid.set(pack_cell(static_cast<std::uint32_t>(side) - 1, 0,
                           static_cast<std::uint32_t>(side) - 1));
        esf::detail::VoxelGrid expected;
        expected.clear();
        for (int z = 0; z < side; ++z)
            for (int y = 0; y < side; ++y)
                for (int x = 0; x < side; ++x) {
                    bool near = false;
                    for (int dz = -1; dz <= 1; ++dz)
                        for (int dy = -1; dy <= 1; ++dy)
                            for (int dx = -1; dx <= 1; ++dx) {
                                const int a = x + dx, b = y + dy, c = z + dz;
                                if (a >= 0 && b >= 0 && c >= 0 && a < side && b < side && c < side)
                                    near = near || grid.occupied(pack_cell(a, b, c));
                            }
                    if (near) expected.set(pack_cell(x, y, z));
                }
        for (const auto simd : {esf::detail::SimdLevel::kAvx512, esf::detail::SimdLevel::kAvx2,
                                esf::detail::SimdLevel::kPortable}) {
            esf::detail::VoxelGrid dilated = grid;
            dilated.dilate(side, simd);
            EXPECT_EQ(dilated.words, expected.words)
                << "side " << side << " simd level " << static_cast<int>(simd);
        }
    }
}

/// `count` lines between random pairs of `points`.
struct RandomLines {
    std::vector<std::uint32_t> starts, ends;
};

RandomLines lines_between(const std::vector<std::uint32_t>& points, std::size_t count,
                          std::mt19937& rng) {
    RandomLines lines{std::vector<std::uint32_t>(count), std::vector<std::uint32_t>(count)};
    std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
    for (std::size_t i = 0; i < count; ++i)
        lines.starts[i] = points[pick(rng)], lines.ends[i] = points[pick(rng)];
    return lines;
}

/// The kernel's counts for `lines` equal the scalar reference's.
void expect_kernel_matches_scalar(const esf::detail::VoxelGrid& grid, const RandomLines& lines,
                                  esf::Kernels kernel, esf::detail::LineEnds ends_hint,
                                  esf::detail::TraceScratch& scratch, const std::string& context) {
    const std::size_t n = lines.starts.size();
    std::vector<std::uint32_t> expected(n), actual(n);
    std::vector<std::uint8_t> expected_visited(n), actual_visited(n);
    esf::detail::trace_lines_scalar(grid, lines.starts, lines.ends, expected, expected_visited);
    esf::detail::trace_lines(grid, lines.starts, lines.ends, actual, actual_visited, scratch,
                             kernel, ends_hint);
    EXPECT_EQ(actual, expected) << context;
    EXPECT_EQ(actual_visited, expected_visited) << context;
}

// As a descriptor's lines: between cells set before the dilation, in a sparse grid whose empty
// rows and grid borders are where the cube look-ups of the AVX-512 kernel can go wrong.
TEST(LineTrace, SimdKernelsMatchScalarBetweenPointCellsOfASparseGrid) {
    std::mt19937 rng(11);
    std::uniform_int_distribution<std::uint32_t> coord(0, 63), edge(0, 1);
    esf::detail::VoxelGrid grid;
    grid.clear();
    std::vector<std::uint32_t> points;
    for (int i = 0; i < 300; ++i) {
        // Half of the points on a face of the grid, so that lines run along its borders.
        std::uint32_t c[3] = {coord(rng), coord(rng), coord(rng)};
        if (i % 2 == 0) c[i % 3] = 63 * edge(rng);
        points.push_back(pack_cell(c[0], c[1], c[2]));
        grid.set(points.back());
    }
    grid.dilate(64);
    const RandomLines lines = lines_between(points, 20011, rng);
    for (auto ends_hint : {esf::detail::LineEnds::kAny, esf::detail::LineEnds::kSetBeforeDilation})
        for (auto kernel : kSimdKernels) {
            esf::detail::TraceScratch scratch;
            expect_kernel_matches_scalar(grid, lines, kernel, ends_hint, scratch, "");
        }
}

// Every count of lines from 1 to 40: the bucketing's rounds of eight lines and its tail, alone
// and together, with repeated lengths in a round (few point cells).
TEST(LineTrace, SimdKernelsMatchScalarOnFewLines) {
    std::mt19937 rng(13);
    std::uniform_int_distribution<std::uint32_t> coord(0, 63);
    esf::detail::VoxelGrid grid;
    grid.clear();
    std::vector<std::uint32_t> points;
    for (int i = 0; i < 6; ++i) {
        points.push_back(pack_cell(coord(rng), coord(rng), coord(rng)));
        grid.set(points.back());
    }
    grid.dilate(64);
    for (std::size_t n = 1; n <= 40; ++n) {
        const RandomLines lines = lines_between(points, n, rng);
        for (auto kernel : kSimdKernels) {
            esf::detail::TraceScratch scratch;
            expect_kernel_matches_scalar(grid, lines, kernel,
                                         esf::detail::LineEnds::kSetBeforeDilation, scratch,
                                         std::to_string(n) + " lines");
        }
    }
}

/// `count` point cells in corner `corner` (bit k: the high end of axis k) of the grid, set in
/// `grid` (cleared first, dilated after).
std::vector<std::uint32_t> corner_cells(std::uint32_t corner, int count,
                                        esf::detail::VoxelGrid& grid, std::mt19937& rng) {
    std::uniform_int_distribution<std::uint32_t> coord(0, 40);
    grid.clear();
    std::vector<std::uint32_t> points;
    for (int i = 0; i < count; ++i) {
        std::uint32_t c[3];
        for (int k = 0; k < 3; ++k) c[k] = (corner >> k & 1) ? 63 - coord(rng) : coord(rng);
        points.push_back(pack_cell(c[0], c[1], c[2]));
        grid.set(points.back());
    }
    grid.dilate(64);
    return points;
}

// One scratch serves many grids, as in an estimator: tables built for one grid must not leak
// into the next (each grid fills a different corner of the cube).
TEST(LineTrace, SimdKernelsReuseTheirScratchAcrossGrids) {
    std::mt19937 rng(5);
    for (auto kernel : kSimdKernels) {
        esf::detail::TraceScratch scratch;
        for (std::uint32_t corner = 0; corner < 8; ++corner) {
            esf::detail::VoxelGrid grid;
            const std::vector<std::uint32_t> points = corner_cells(corner, 200, grid, rng);
            expect_kernel_matches_scalar(grid, lines_between(points, 5003, rng), kernel,
                                         esf::detail::LineEnds::kSetBeforeDilation, scratch,
                                         "corner " + std::to_string(corner));
        }
    }
}

// An estimator's scratch serves whichever tracer its trials pick for each call: the cube table
// one kernel built for a grid must be cleared right when another kernel builds it for the next.
TEST(LineTrace, SimdKernelsTakeTurnsOnOneScratch) {
    std::mt19937 rng(9);
    esf::detail::TraceScratch scratch;
    for (std::uint32_t turn = 0; turn < 12; ++turn) {
        const esf::Kernels kernel = kSimdKernels[turn % std::size(kSimdKernels)];
        esf::detail::VoxelGrid grid;
        const std::vector<std::uint32_t> points = corner_cells(turn % 8, 150, grid, rng);
        expect_kernel_matches_scalar(grid, lines_between(points, 3001, rng), kernel,
                                     esf::detail::LineEnds::kSetBeforeDilation, scratch,
                                     "turn " + std::to_string(turn));
    }
}

/// A line of `length` steps along `axis` (0, 1, 2) from a random cell, up the axis; its minor
/// axes move at most `length` cells either way, at random.
std::pair<std::uint32_t, std::uint32_t> line_along(int axis, std::uint32_t length,
                                                   std::mt19937& rng) {
    std::uniform_int_distribution<std::uint32_t> major(0, 63 - length), minor(0, 63);
    std::uint32_t from[3], to[3];
    from[axis] = major(rng);
    to[axis] = from[axis] + length;
    const int m1 = axis == 0 ? 1 : 0, m2 = axis == 2 ? 1 : 2;  // the minor axes, in order
    for (const int m : {m1, m2}) from[m] = minor(rng);
    for (const int m : {m1, m2}) {
        std::uniform_int_distribution<std::uint32_t> end(from[m] >= length ? from[m] - length : 0,
                                                         std::min(63u, from[m] + length));
        to[m] = end(rng);
    }
    return {pack_cell(from[0], from[1], from[2]), pack_cell(to[0], to[1], to[2])};
}

// Lines of one length in whole groups of 16 (and a few more), for every length: groups whose
// lanes all end at the same cell finish without per-lane masks in the AVX-512 kernel.
TEST(LineTrace, SimdKernelsMatchScalarOnGroupsOfOneLength) {
    std::mt19937 rng(17);
    esf::detail::VoxelGrid grid;
    grid.clear();
    std::uniform_int_distribution<std::uint32_t> coord(0, 63);
    std::vector<std::uint32_t> points;
    for (int i = 0; i < 2000; ++i) {
        points.push_back(pack_cell(coord(rng), coord(rng), coord(rng)));
        grid.set(points.back());
    }
    grid.dilate(64);
    RandomLines lines;
    for (std::uint32_t length = 0; length < 64; ++length)
        for (int k = 0; k < 32 + static_cast<int>(length % 5); ++k) {
            const auto [a, b] = line_along(0, length, rng);
            lines.starts.push_back(k % 2 ? a : b);
            lines.ends.push_back(k % 2 ? b : a);
        }
    for (auto kernel : kSimdKernels) {
        esf::detail::TraceScratch scratch;
        expect_kernel_matches_scalar(grid, lines, kernel, esf::detail::LineEnds::kAny, scratch, "");
    }
}

// Lengths whose lines fill several of the AVX-512 kernel's chunks of 256 lines exactly, by one
// line more or one less, in shuffled order: every chunk boundary and last, partly filled group.
TEST(LineTrace, SimdKernelsMatchScalarWhenOneLengthFillsSeveralChunks) {
    std::mt19937 rng(29);
    esf::detail::VoxelGrid grid;
    grid.clear();
    std::uniform_int_distribution<std::uint32_t> coord(0, 63);
    for (int i = 0; i < 3000; ++i) grid.set(pack_cell(coord(rng), coord(rng), coord(rng)));
    grid.dilate(64);
    RandomLines lines;
    const std::pair<std::uint32_t, int> lengths[] = {{7, 255},  {9, 256},   {12, 257},
                                                     {20, 512}, {30, 1001}, {63, 3}};
    for (const auto& [length, count] : lengths)
        for (int k = 0; k < count; ++k) {
            const auto [a, b] = line_along(2, length, rng);
            lines.starts.push_back(a);
            lines.ends.push_back(b);
        }
    std::vector<std::size_t> order(lines.starts.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::shuffle(order.begin(), order.end(), rng);
    RandomLines shuffled;
    for (const std::size_t i : order) {
        shuffled.starts.push_back(lines.starts[i]);
        shuffled.ends.push_back(lines.ends[i]);
    }
    for (auto kernel : kSimdKernels) {
        esf::detail::TraceScratch scratch;
        expect_kernel_matches_scalar(grid, shuffled, kernel, esf::detail::LineEnds::kAny, scratch,
                                     "");
    }
}

}  // namespace

// The first call runs the widest kernel and its time does not count (cold caches): recorded
// here as far faster than any later call, so that counting it would change every choice below.
namespace {
void warm_up(esf::detail::TraceKernelTrials& trials) {
    for (int i = 0; i < esf::detail::TraceKernelTrials::kWarmUpCalls; ++i) {
        ASSERT_EQ(trials.next(), esf::Kernels::kBest);
        trials.record(esf::Kernels::kBest, 1e-6, 1000);
    }
}
}  // namespace

// Times are compared per visited cell (calls trace different clouds), and a narrower kernel must
// beat the widest by the margin.
TEST(TraceKernelTrials, ComparesTimePerCellAndKeepsTheWidestWithinTheMargin) {
    using esf::Kernels;
    using esf::detail::TraceKernelTrials;
    for (const double narrower_speed : {0.98, 0.90}) {  // time per cell against the widest
        TraceKernelTrials trials;
        if (trials.decided()) return;  // one kernel on this CPU
        warm_up(trials);
        while (!trials.decided()) {
            const Kernels kernel = trials.next();
            // The widest traces twice the cells in twice the time: the same time per cell.
            if (kernel == Kernels::kBest)
                trials.record(kernel, 2.0, 2000);
            else
                trials.record(kernel, narrower_speed, 1000);
        }
        EXPECT_EQ(trials.next() == Kernels::kBest,
                  narrower_speed > 1.0 - TraceKernelTrials::kMargin)
            << narrower_speed;
    }
}

// A narrower kernel far slower than the widest takes no more turns after the round in which it
// fell behind; one within kDrop takes all its turns.
TEST(TraceKernelTrials, DropsKernelsFarSlowerThanTheWidestAfterARound) {
    using esf::Kernels;
    using esf::detail::TraceKernelTrials;
    {
        TraceKernelTrials trials;
        if (trials.decided()) return;  // one kernel on this CPU
    }
    for (const double slower :
         {1.0 + TraceKernelTrials::kDrop + 0.05, 1.0 + TraceKernelTrials::kDrop - 0.05}) {
        TraceKernelTrials trials;
        warm_up(trials);
        std::vector<Kernels> tried;
        while (!trials.decided() && tried.size() < 100) {
            const Kernels kernel = trials.next();
            tried.push_back(kernel);
            trials.record(kernel, kernel == Kernels::kBest ? 1.0 : slower, 1000);
        }
        ASSERT_TRUE(trials.decided());
        EXPECT_EQ(trials.next(), Kernels::kBest) << slower;
        const std::size_t kinds = static_cast<std::size_t>(
            std::find(tried.begin() + 1, tried.end(), Kernels::kBest) - tried.begin());
        if (slower > 1.0 + TraceKernelTrials::kDrop) {
            // One round, then the widest alone is left: chosen at once.
            EXPECT_EQ(tried.size(), kinds) << slower;
        } else {
            EXPECT_EQ(tried.size(), kinds * TraceKernelTrials::kRounds) << slower;
        }
    }
    // Dropped after the second round: the narrower kernels were as fast as the widest in the
    // first, then the widest got twice as fast.
    TraceKernelTrials trials;
    warm_up(trials);
    std::vector<Kernels> tried;
    while (!trials.decided() && tried.size() < 100) {
        const Kernels kernel = trials.next();
        const bool widest_again = kernel == Kernels::kBest && !tried.empty();
        tried.push_back(kernel);
        trials.record(kernel, widest_again ? 0.5 : 1.0, 1000);
    }
    ASSERT_TRUE(trials.decided());
    EXPECT_EQ(trials.next(), Kernels::kBest);
    const auto kinds = static_cast<std::size_t>(
        std::find(tried.begin() + 1, tried.end(), Kernels::kBest) - tried.begin());
    EXPECT_EQ(tried.size(), 2 * kinds);
}

TEST(TraceKernelTrials, TriesEachKernelInTurnThenKeepsTheFastest) {
    using esf::Kernels;
    esf::detail::TraceKernelTrials trials;
    if (trials.decided()) {  // a CPU with one kernel: nothing to try
        EXPECT_EQ(trials.next(), Kernels::kBest);
        return;
    }
    warm_up(trials);
    std::vector<Kernels> tried;
    while (!trials.decided() && tried.size() < 100) {
        const Kernels kernel = trials.next();
        tried.push_back(kernel);
        // The AVX2 kernel is made the fastest after the first round (at most three kernels).
        const bool later_round = tried.size() > 3;
        trials.record(kernel, kernel == Kernels::kAvx2 && later_round ? 1.0 : 2.0, 1000);
    }
    ASSERT_TRUE(trials.decided());
    const std::size_t kinds = tried.size() / esf::detail::TraceKernelTrials::kRounds;
    ASSERT_EQ(tried.size(), kinds * esf::detail::TraceKernelTrials::kRounds);
    EXPECT_EQ(tried.front(), Kernels::kBest);  // the widest first
    for (std::size_t i = kinds; i < tried.size(); ++i) EXPECT_EQ(tried[i], tried[i - kinds]);
    EXPECT_EQ(trials.next(), Kernels::kAvx2);
    trials.record(Kernels::kAvx2, 100.0, 1000);  // the choice stays
    EXPECT_EQ(trials.next(), Kernels::kAvx2);
}
