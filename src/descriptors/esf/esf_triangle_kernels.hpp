#pragma once
// Internal: what the triangle sampler and the histograms share across their portable code
// (esf_triangles.cpp, esf_histograms.cpp) and their AVX2 and AVX-512 kernels
// (esf_triangles_avx2.cpp, esf_triangles_avx512.cpp, esf_histograms_avx2.cpp,
// esf_histograms_avx512.cpp): the constants, the random streams, and the kernels' entry points.
// Each kernel carries ESF_TARGET_AVX2 or ESF_TARGET_AVX512 and runs only where the CPU has it;
// every file is compiled with -ffp-contract=off, so that all of them round alike.

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <numbers>

#include "core/splitmix64.hpp"
#include "descriptors/esf/esf_triangles.hpp"

namespace esf::detail {

/// The AVX2 kernels take a block of kLanes as two halves of kHalf lanes.
inline constexpr int kHalf = 8;

// Line and triangle classes of the reference: a line is IN when at most one of its cells is
// empty, OUT when at most 7 are occupied; a triangle is OUT when its three lines hold at most 21
// occupied cells, IN when at most 3 of their cells are empty.
inline constexpr int kLineOutMaxOccupied = 7;
inline constexpr int kTriangleOutMaxOccupied = 21;
inline constexpr int kTriangleInMaxEmpty = 3;
// The counts: four interleaved copies of blocks 0-7 (A3, D3, D2 IN and OUT), lane l counting into
// copy l % 4 so that consecutive increments of one bin do not wait on each other's stores; then
// one joint histogram of the MIXED lines over (D2 bin, ratio bin), whose row and column sums are
// blocks 8 (D2 MIXED) and 9 (ratio). Every line then costs one increment instead of two.
inline constexpr int kCopies = 4;
inline constexpr int kCopyBins = 8 * kEsfBins;
inline constexpr int kJointBase = kCopies * kCopyBins;
inline constexpr int kCountBins = kJointBase + kEsfBins * kEsfBins;

/// Position of a MIXED line's joint bin, relative to the copy lane l counts into.
constexpr std::uint32_t joint_bin(std::size_t lane, int d2_bin, int ratio_bin) {
    return static_cast<std::uint32_t>(kJointBase - static_cast<int>(lane % kCopies) * kCopyBins +
                                      d2_bin * kEsfBins + ratio_bin);
}

// acos(x) = sqrt(1 - x) * (a0 + a1 x + ... + a7 x^7) on [0, 1] (A&S 4.4.46).
inline constexpr float kAcos[8] = {1.5707963050f, -0.2145988016f, 0.0889789874f, -0.0501743046f,
                                   0.0308918810f, -0.0170881256f, 0.0066700901f, -0.0012624911f};
inline constexpr float kBinsPerRadian = static_cast<float>(kTopBin / (std::numbers::pi / 2.0));
inline constexpr float kPi = std::numbers::pi_v<float>;

/// 16 xoshiro128++ streams (Blackman & Vigna), state word w of lane l in s[w][l].
struct Streams {
    alignas(64) std::uint32_t s[4][kLanes];

    explicit Streams(std::uint64_t seed) {
        std::uint64_t state = seed;
        for (int l = 0; l < kLanes; ++l) {
            const std::uint64_t a = splitmix64(state), b = splitmix64(state);
            s[0][l] = static_cast<std::uint32_t>(a);
            s[1][l] = static_cast<std::uint32_t>(a >> 32);
            s[2][l] = static_cast<std::uint32_t>(b);
            s[3][l] = static_cast<std::uint32_t>(b >> 32);
            if ((s[0][l] | s[1][l] | s[2][l] | s[3][l]) == 0) s[0][l] = 1;  // never all zero
        }
    }
    std::uint32_t next(int l) {
        std::uint32_t &s0 = s[0][l], &s1 = s[1][l], &s2 = s[2][l], &s3 = s[3][l];
        const std::uint32_t result = std::rotl(s0 + s3, 7) + s0;
        const std::uint32_t t = s1 << 9;
        s2 ^= s0;
        s3 ^= s1;
        s1 ^= s2;
        s0 ^= s3;
        s2 ^= t;
        s3 = std::rotl(s3, 11);
        return result;
    }
};

/// Uniform index in [0, n) from 32 random bits (Lemire's multiply-shift).
inline std::uint32_t bounded(std::uint32_t bits, std::uint32_t n) {
    return static_cast<std::uint32_t>((std::uint64_t{bits} * n) >> 32);
}

/// The lowest `n` set bits of `mask`.
inline std::uint32_t lowest_bits(std::uint32_t mask, int n) {
    for (int excess = std::popcount(mask) - n; excess > 0; --excess)
        mask &= ~(std::uint32_t{1} << (31 - std::countl_zero(mask)));
    return mask;
}

/// Histogram positions of 16 triangles, relative to the copy of each lane: bins[slot][lane],
/// slots 0-2 the lines (D2 IN or OUT, or the joint bin of a MIXED line), 3 D3, 4-6 A3 with
/// weights weight[0..2].
struct HistogramBlock {
    alignas(64) std::uint32_t bins[7][kLanes];
    alignas(64) std::uint32_t weight[3][kLanes];
};

// The kernels of each instruction set; the callers check the CPU first (core/simd.hpp).

/// sample_triangles_fast() with AVX-512: the 16 streams as one vector.
SampleCount sample_triangles_avx512(const PackedPoint* points, std::uint32_t count,
                                    std::uint64_t seed, std::size_t max_attempts, float min_heron,
                                    TriangleSet& set);
/// sample_triangles_fast() with AVX2: the 16 streams as two halves of 8 lanes.
SampleCount sample_triangles_avx2(const PackedPoint* points, std::uint32_t count,
                                  std::uint64_t seed, std::size_t max_attempts, float min_heron,
                                  TriangleSet& set);

/// The A3 bins (triangle_angle_bins()) of the first triangles of `set`, 16 (AVX-512) or 8
/// (AVX2) at a time, as many as whole steps cover of `count`; returns how many.
std::size_t angle_bins_avx512(TriangleSet& set, std::size_t count);
std::size_t angle_bins_avx2(TriangleSet& set, std::size_t count);

/// The histogram positions of the 16 triangles first .. first + 15 (all accepted), as the
/// portable code forms them with the reciprocal scales d2_scale and d3_scale.
void histogram_block_avx512(const TriangleSet& set, const std::uint32_t* occupied,
                            const std::uint8_t* visited, std::size_t first, float d2_scale,
                            float d3_scale, HistogramBlock& block);
void histogram_block_avx2(const TriangleSet& set, const std::uint32_t* occupied,
                          const std::uint8_t* visited, std::size_t first, float d2_scale,
                          float d3_scale, HistogramBlock& block);

}  // namespace esf::detail
