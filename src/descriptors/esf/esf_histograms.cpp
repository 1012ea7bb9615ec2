// The ten histograms of the ESF descriptor from the triangles and the cells of their lines:
// the portable code and the choice of kernel.

#include <algorithm>
#include <cstring>

#include "descriptors/esf/esf_triangle_kernels.hpp"
#include "descriptors/esf/esf_triangles.hpp"

namespace esf::detail {

namespace {

void histogram_block_scalar(const TriangleSet& set, const std::uint32_t* occupied,
                            const std::uint8_t* visited, std::size_t first, std::size_t lanes,
                            bool pcl_division, float d2_scale, float d3_scale,
                            HistogramBlock& block) {
    const std::size_t s = set.samples;
    for (std::size_t l = 0; l < lanes; ++l) {
        const std::size_t t = first + l;
        int o[3], v[3];
        for (int k = 0; k < 3; ++k) {
            o[k] = occupied[static_cast<std::size_t>(k) * s + t];
            v[k] = visited[static_cast<std::size_t>(k) * s + t];
            const bool in = o[k] + 1 >= v[k];
            const bool out = !in && o[k] <= kLineOutMaxOccupied;
            const bool mixed = !in && !out;
            const float d = set.d2[static_cast<std::size_t>(k) * s + t];
            const int bin =
                std::min(round_bin(pcl_division ? d / set.max_d2 * static_cast<float>(kTopBin)
                                                : d * d2_scale),
                         kTopBin);
            const float ratio = static_cast<float>(o[k]) / static_cast<float>(v[k]);
            block.bins[k][l] =
                mixed ? joint_bin(l, bin, round_bin(ratio * static_cast<float>(kTopBin)))
                      : static_cast<std::uint32_t>((out ? 7 : 6) * kEsfBins + bin);
        }
        const int occupied_sum = o[0] + o[1] + o[2], visited_sum = v[0] + v[1] + v[2];
        const bool out = occupied_sum <= kTriangleOutMaxOccupied;
        const bool in = !out && visited_sum - occupied_sum <= kTriangleInMaxEmpty;
        const int cls = out ? 1 : in ? 0 : 2;
        const float d3 = set.d3[t];
        const int d3_bin = std::min(
            round_bin(pcl_division ? d3 / set.max_d3 * static_cast<float>(kTopBin) : d3 * d3_scale),
            kTopBin);
        block.bins[3][l] = static_cast<std::uint32_t>((3 + cls) * 64 + d3_bin);
        const std::uint32_t angles = set.angle_bins[t];
        for (int k = 0; k < 3; ++k)
            block.bins[4 + k][l] = static_cast<std::uint32_t>(cls * 64) + (angles >> (8 * k) & 255);
        // Each angle is weighted by the visited cells of the line opposite to it.
        block.weight[0][l] = static_cast<std::uint32_t>(v[2]);
        block.weight[1][l] = static_cast<std::uint32_t>(v[0]);
        block.weight[2][l] = static_cast<std::uint32_t>(v[1]);
    }
}

}  // namespace

EsfCounts histogram_triangles(const TriangleSet& set, const std::uint32_t* occupied,
                              const std::uint8_t* visited, bool pcl_division, SimdLevel simd) {
    std::array<std::uint32_t, kCountBins> tally{};  // see kCopies
    // The fast sampler multiplies by the reciprocal of the maximum (a last-bit difference at a
    // bin border, far below the sampling noise).
    const float d2_scale = static_cast<float>(kTopBin) / set.max_d2;
    const float d3_scale = static_cast<float>(kTopBin) / set.max_d3;
    const SimdLevel vector = pcl_division ? SimdLevel::kPortable : simd;
    // Each block's bins are formed one block ahead of their increments: the increments read
    // what the vector stores wrote a block earlier instead of waiting on them.
    HistogramBlock blocks[2];
    const auto form = [&](std::size_t first, HistogramBlock& block) {
        const std::size_t lanes = std::min<std::size_t>(kLanes, set.samples - first);
        if (vector == SimdLevel::kAvx512 && lanes == kLanes)
            histogram_block_avx512(set, occupied, visited, first, d2_scale, d3_scale, block);
        else if (vector == SimdLevel::kAvx2 && lanes == kLanes)
            histogram_block_avx2(set, occupied, visited, first, d2_scale, d3_scale, block);
        else
            histogram_block_scalar(set, occupied, visited, first, lanes, pcl_division, d2_scale,
                                   d3_scale, block);
    };
    if (set.samples > 0) form(0, blocks[0]);
    for (std::size_t first = 0, turn = 0; first < set.samples; first += kLanes, turn ^= 1) {
        const std::size_t lanes = std::min<std::size_t>(kLanes, set.samples - first);
        if (first + kLanes < set.samples) form(first + kLanes, blocks[turn ^ 1]);
        const HistogramBlock& block = blocks[turn];
        // Four lanes at a time, one per copy, their increments interleaved: a triangle's next
        // increment to its copy comes three others later, so a repeated bin (two lines of one
        // triangle in one bin) does not wait on the store before. Two lanes' positions per load
        // (the increments are bound by memory operations).
        static_assert(kCopies == 4);
        std::size_t l = 0;
        for (; l + 4 <= lanes; l += 4) {
            std::uint32_t* copy[4];
            for (std::size_t c = 0; c < 4; ++c) copy[c] = tally.data() + c * kCopyBins;
            for (int k = 0; k < 4; ++k) {
                std::uint64_t low, high;
                std::memcpy(&low, &block.bins[k][l], sizeof low);
                std::memcpy(&high, &block.bins[k][l + 2], sizeof high);
                ++copy[0][static_cast<std::uint32_t>(low)];
                ++copy[1][low >> 32];
                ++copy[2][static_cast<std::uint32_t>(high)];
                ++copy[3][high >> 32];
            }
            for (int k = 0; k < 3; ++k) {
                std::uint64_t low, high, low_weights, high_weights;
                std::memcpy(&low, &block.bins[4 + k][l], sizeof low);
                std::memcpy(&high, &block.bins[4 + k][l + 2], sizeof high);
                std::memcpy(&low_weights, &block.weight[k][l], sizeof low_weights);
                std::memcpy(&high_weights, &block.weight[k][l + 2], sizeof high_weights);
                copy[0][static_cast<std::uint32_t>(low)] += static_cast<std::uint32_t>(low_weights);
                copy[1][low >> 32] += static_cast<std::uint32_t>(low_weights >> 32);
                copy[2][static_cast<std::uint32_t>(high)] +=
                    static_cast<std::uint32_t>(high_weights);
                copy[3][high >> 32] += static_cast<std::uint32_t>(high_weights >> 32);
            }
        }
        for (; l < lanes; ++l) {
            std::uint32_t* h = tally.data() + (l % kCopies) * kCopyBins;
            for (int k = 0; k < 4; ++k) ++h[block.bins[k][l]];
            for (int k = 0; k < 3; ++k) h[block.bins[4 + k][l]] += block.weight[k][l];
        }
    }
    EsfCounts counts{};
    for (int b = 0; b < 8; ++b)
        for (int i = 0; i < kEsfBins; ++i) {
            std::uint32_t total = 0;
            for (int c = 0; c < kCopies; ++c)
                total += tally[static_cast<std::size_t>(c * kCopyBins + b * kEsfBins + i)];
            counts[static_cast<std::size_t>(b)][static_cast<std::size_t>(i)] = total;
        }
    // Blocks 8 (D2 of the MIXED lines) and 9 (their ratio): the joint histogram's row and
    // column sums.
    const std::uint32_t* joint = tally.data() + kJointBase;
    for (std::size_t d2 = 0; d2 < kEsfBins; ++d2)
        for (std::size_t ratio = 0; ratio < kEsfBins; ++ratio) {
            const std::uint32_t n = joint[d2 * kEsfBins + ratio];
            counts[8][d2] += n;
            counts[9][ratio] += n;
        }
    return counts;
}

}  // namespace esf::detail
