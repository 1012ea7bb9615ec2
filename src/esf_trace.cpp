#include "esf_trace.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cassert>
#include <cstdlib>

namespace esf::detail {

void VoxelGrid::dilate(int side) {
    // The 3x3x3 box is separable: dilate along x (bits), then y (rows), then z (slices).
    const std::uint64_t x_mask = side >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << side) - 1;
    for (auto& word : words) word = (word | (word << 1) | (word >> 1)) & x_mask;
    std::array<std::uint64_t, kGridWords> src = words;
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

namespace {

/// Per-line Bresenham set-up, on linear cell indices: the major axis steps every cell, each
/// minor axis steps when its error term is positive (pcl::ESFEstimation::lci).
struct LineSetup {
    std::int32_t start;
    std::int32_t major_step;  // +-1, +-64 or +-4096
    std::int32_t minor_step[2];
    std::int32_t error[2];      // 2 a_m - L
    std::int32_t increment[2];  // 2 a_m
    std::int32_t decrement;     // 2 L
    std::int32_t visited;       // max(L, 1)
};

inline LineSetup setup_line(std::uint32_t start, std::uint32_t end) {
    int delta[3], length[3], step[3];
    for (int axis = 0; axis < 3; ++axis) {
        const int shift = axis * kGridBits;
        delta[axis] = static_cast<int>((end >> shift) & 63) - static_cast<int>((start >> shift) & 63);
        length[axis] = std::abs(delta[axis]);
        step[axis] = (delta[axis] < 0 ? -1 : 1) * (1 << shift);
    }
    int major, minor_a, minor_b;  // minor order as in the reference: x: y,z; y: x,z; z: y,x
    if (length[0] >= length[1] && length[0] >= length[2]) {
        major = 0, minor_a = 1, minor_b = 2;
    } else if (length[1] >= length[2]) {
        major = 1, minor_a = 0, minor_b = 2;
    } else {
        major = 2, minor_a = 1, minor_b = 0;
    }
    const int l = length[major];
    return LineSetup{static_cast<std::int32_t>(start),
                     step[major],
                     {step[minor_a], step[minor_b]},
                     {2 * length[minor_a] - l, 2 * length[minor_b] - l},
                     {2 * length[minor_a], 2 * length[minor_b]},
                     2 * l,
                     l > 0 ? l : 1};
}

inline std::uint16_t trace_one(const VoxelGrid& grid, const LineSetup& line) {
    std::int32_t cell = line.start;
    std::int32_t e0 = line.error[0], e1 = line.error[1];
    std::uint32_t occupied = 0;
    for (std::int32_t i = 0; i < line.visited; ++i) {
        occupied += grid.occupied(static_cast<std::uint32_t>(cell));
        const bool s0 = e0 > 0, s1 = e1 > 0;
        cell += line.major_step + (s0 ? line.minor_step[0] : 0) + (s1 ? line.minor_step[1] : 0);
        e0 += line.increment[0] - (s0 ? line.decrement : 0);
        e1 += line.increment[1] - (s1 ? line.decrement : 0);
    }
    return static_cast<std::uint16_t>(occupied);
}

/// Orders lines by visited count so that SIMD lanes of one group run equally long.
void sort_by_length(std::span<const std::uint32_t> starts, std::span<const std::uint32_t> ends,
                    TraceScratch& scratch) {
    const std::size_t count = starts.size();
    scratch.bucket_start.assign(kGridSide + 1, 0);
    scratch.order.resize(count);
    auto& bucket = scratch.bucket_start;
    std::vector<std::uint8_t> lengths(count);  // small; kept local for clarity
    for (std::size_t i = 0; i < count; ++i) {
        lengths[i] = static_cast<std::uint8_t>(visited_cells(starts[i], ends[i]));
        ++bucket[lengths[i]];
    }
    std::uint32_t sum = 0;
    for (auto& b : bucket) {
        const std::uint32_t c = b;
        b = sum;
        sum += c;
    }
    for (std::size_t i = 0; i < count; ++i)
        scratch.order[bucket[lengths[i]]++] = static_cast<std::uint32_t>(i);
}

__attribute__((target("avx2"))) void trace_lines_avx2(const VoxelGrid& grid,
                                                      std::span<const std::uint32_t> starts,
                                                      std::span<const std::uint32_t> ends,
                                                      std::span<std::uint16_t> occupied,
                                                      TraceScratch& scratch) {
    sort_by_length(starts, ends, scratch);
    const auto* words32 = reinterpret_cast<const int*>(grid.words.data());
    const std::size_t count = starts.size();
    const __m256i one = _mm256_set1_epi32(1), low5 = _mm256_set1_epi32(31);
    alignas(32) std::int32_t lane[9][8];
    for (std::size_t group = 0; group < count; group += 8) {
        const std::size_t lanes = std::min<std::size_t>(8, count - group);
        std::int32_t steps = 0;
        for (std::size_t k = 0; k < 8; ++k) {
            LineSetup s{};  // padding lanes visit nothing
            if (k < lanes) {
                const std::uint32_t id = scratch.order[group + k];
                s = setup_line(starts[id], ends[id]);
            }
            lane[0][k] = s.start, lane[1][k] = s.major_step;
            lane[2][k] = s.minor_step[0], lane[3][k] = s.minor_step[1];
            lane[4][k] = s.error[0], lane[5][k] = s.error[1];
            lane[6][k] = s.increment[0], lane[7][k] = s.increment[1];
            lane[8][k] = s.visited;
            steps = std::max(steps, s.visited);
        }
#define ESF_LANES(row) _mm256_load_si256(reinterpret_cast<const __m256i*>(lane[row]))
        __m256i cell = ESF_LANES(0), e0 = ESF_LANES(4), e1 = ESF_LANES(5);
        __m256i remaining = ESF_LANES(8);
        const __m256i major = ESF_LANES(1), step0 = ESF_LANES(2), step1 = ESF_LANES(3);
        const __m256i inc0 = ESF_LANES(6), inc1 = ESF_LANES(7);
#undef ESF_LANES
        // 2 L per lane: e0 = 2 a0 - L and inc0 = 2 a0, so L = inc0 - e0.
        const __m256i decrement = _mm256_slli_epi32(_mm256_sub_epi32(inc0, e0), 1);
        __m256i count_in = _mm256_setzero_si256();
        for (std::int32_t i = 0; i < steps; ++i) {
            const __m256i active = _mm256_cmpgt_epi32(remaining, _mm256_setzero_si256());
            const __m256i word =
                _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), words32,
                                            _mm256_srli_epi32(cell, 5), active, 4);
            const __m256i bit = _mm256_and_si256(_mm256_srlv_epi32(word, _mm256_and_si256(cell, low5)), one);
            count_in = _mm256_add_epi32(count_in, _mm256_and_si256(bit, active));
            remaining = _mm256_sub_epi32(remaining, one);
            const __m256i s0 = _mm256_cmpgt_epi32(e0, _mm256_setzero_si256());
            const __m256i s1 = _mm256_cmpgt_epi32(e1, _mm256_setzero_si256());
            cell = _mm256_add_epi32(cell, major);
            cell = _mm256_add_epi32(cell, _mm256_and_si256(s0, step0));
            cell = _mm256_add_epi32(cell, _mm256_and_si256(s1, step1));
            e0 = _mm256_add_epi32(e0, _mm256_sub_epi32(inc0, _mm256_and_si256(s0, decrement)));
            e1 = _mm256_add_epi32(e1, _mm256_sub_epi32(inc1, _mm256_and_si256(s1, decrement)));
        }
        alignas(32) std::int32_t result[8];
        _mm256_store_si256(reinterpret_cast<__m256i*>(result), count_in);
        for (std::size_t k = 0; k < lanes; ++k)
            occupied[scratch.order[group + k]] = static_cast<std::uint16_t>(result[k]);
    }
}

bool has_avx2() {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2");
}

}  // namespace

void trace_lines_scalar(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                        std::span<const std::uint32_t> ends, std::span<std::uint16_t> occupied) {
    assert(starts.size() == ends.size() && occupied.size() == starts.size());
    for (std::size_t i = 0; i < starts.size(); ++i)
        occupied[i] = trace_one(grid, setup_line(starts[i], ends[i]));
}

void trace_lines(const VoxelGrid& grid, std::span<const std::uint32_t> starts,
                 std::span<const std::uint32_t> ends, std::span<std::uint16_t> occupied,
                 TraceScratch& scratch) {
    static const bool avx2 = has_avx2();
    if (avx2) {
        trace_lines_avx2(grid, starts, ends, occupied, scratch);
    } else {
        trace_lines_scalar(grid, starts, ends, occupied);
    }
}

const char* trace_kernel_name() { return has_avx2() ? "avx2" : "scalar"; }

}  // namespace esf::detail
