#include "descriptors/esf/esf_triangles.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include "descriptors/esf/esf_triangle_kernels.hpp"

namespace esf::detail {

void TriangleSet::resize(std::size_t count) {
    samples = count;
    angle_bins.resize(count + 16);  // + one block of slack for masked full-width stores
    d2.resize(3 * count + 16);
    d3.resize(count + 16);
    line_start.resize(3 * count + 16);
    line_end.resize(3 * count + 16);
    max_d2 = max_d3 = 0.0f;
}

namespace {

/// One block of 16 attempts, lane by lane.
struct Block {
    std::uint32_t index[3][kLanes];
    std::uint32_t cell[3][kLanes];
    float a[kLanes], b[kLanes], c[kLanes], d3[kLanes];
    std::uint32_t accepted = 0;  // lane mask
};

void sample_block_scalar(Streams& streams, const PackedPoint* points, std::uint32_t count,
                         float min_heron, Block& block) {
    block.accepted = 0;
    for (int l = 0; l < kLanes; ++l)
        for (int k = 0; k < 3; ++k) block.index[k][l] = bounded(streams.next(l), count);
    for (int l = 0; l < kLanes; ++l) {
        const PackedPoint& p1 = points[block.index[0][l]];
        const PackedPoint& p2 = points[block.index[1][l]];
        const PackedPoint& p3 = points[block.index[2][l]];
        const float x21 = p2.x - p1.x, y21 = p2.y - p1.y, z21 = p2.z - p1.z;
        const float x31 = p3.x - p1.x, y31 = p3.y - p1.y, z31 = p3.z - p1.z;
        const float x23 = p2.x - p3.x, y23 = p2.y - p3.y, z23 = p2.z - p3.z;
        const float a = std::sqrt(x21 * x21 + y21 * y21 + z21 * z21);
        const float b = std::sqrt(x31 * x31 + y31 * y31 + z31 * z31);
        const float c = std::sqrt(x23 * x23 + y23 * y23 + z23 * z23);
        const float s = (a + b + c) * 0.5f;
        const float heron = s * (s - a) * (s - b) * (s - c);
        const std::uint32_t i1 = block.index[0][l], i2 = block.index[1][l], i3 = block.index[2][l];
        if (i1 == i2 || i1 == i3 || i2 == i3 || !(heron > min_heron)) continue;
        block.accepted |= 1u << l;
        block.a[l] = a, block.b[l] = b, block.c[l] = c;
        block.d3[l] = std::sqrt(std::sqrt(heron));
        block.cell[0][l] = p1.cell, block.cell[1][l] = p2.cell, block.cell[2][l] = p3.cell;
    }
}

/// Appends the lanes of `keep` (in lane order) to the triangle set at `at`.
void commit_scalar(const Block& block, std::uint32_t keep, std::size_t at, TriangleSet& set) {
    const std::size_t s = set.samples;
    for (int l = 0; l < kLanes; ++l) {
        if (!(keep >> l & 1)) continue;
        set.d2[at] = block.a[l], set.d2[s + at] = block.b[l], set.d2[2 * s + at] = block.c[l];
        set.d3[at] = block.d3[l];
        const std::uint32_t c1 = block.cell[0][l], c2 = block.cell[1][l], c3 = block.cell[2][l];
        set.line_start[at] = c1, set.line_end[at] = c2;
        set.line_start[s + at] = c1, set.line_end[s + at] = c3;
        set.line_start[2 * s + at] = c2, set.line_end[2 * s + at] = c3;
        set.max_d2 = std::max({set.max_d2, block.a[l], block.b[l], block.c[l]});
        set.max_d3 = std::max(set.max_d3, block.d3[l]);
        ++at;
    }
}

}  // namespace

float fast_acos(float c) {
    const float x = std::min(c, 1.0f);
    float p = kAcos[7];
    for (int k = 6; k >= 0; --k) p = std::fma(p, x, kAcos[k]);
    return std::sqrt(1.0f - x) * p;
}

float third_angle(float angle1, float angle3, float n1, float n3, float n2) {
    if (n2 < 0.0f) return angle1 + angle3;  // obtuse at p2: pi - (pi - angle1 - angle3)
    if (n1 < 0.0f) return angle1 - angle3;  // obtuse at p1
    if (n3 < 0.0f) return angle3 - angle1;  // obtuse at p3
    return kPi - angle1 - angle3;
}

std::uint32_t triangle_angle_bins(float a, float b, float c) {
    const float aa = a * a, bb = b * b, cc = c * c;
    const float n1 = (aa + bb) - cc, n3 = (bb + cc) - aa, n2 = (aa + cc) - bb;
    const float half_inverse = 0.5f / (a * b * c);
    const float angle1 = fast_acos(std::abs(n1) * (c * half_inverse));
    const float angle3 = fast_acos(std::abs(n3) * (a * half_inverse));
    const float angle2 = third_angle(angle1, angle3, n1, n3, n2);
    return static_cast<std::uint32_t>(angle_bin(angle1)) |
           static_cast<std::uint32_t>(angle_bin(angle3)) << 8 |
           static_cast<std::uint32_t>(angle_bin(angle2)) << 16;
}

int angle_bin(float angle) {
    // Truncation: a difference of angles that rounds a hair below zero still lands in bin 0.
    return std::min(static_cast<int>(angle * kBinsPerRadian + 0.5f), kTopBin);
}

namespace {

SampleCount sample_portable(const PackedPoint* points, std::uint32_t count, std::uint64_t seed,
                            std::size_t max_attempts, float min_heron, TriangleSet& set) {
    Streams streams(seed);
    Block block;
    SampleCount done;
    while (done.accepted < set.samples && done.attempts < max_attempts) {
        sample_block_scalar(streams, points, count, min_heron, block);
        std::uint32_t keep = block.accepted;
        const std::size_t usable = std::min<std::size_t>(kLanes, max_attempts - done.attempts);
        if (usable < kLanes) keep &= (1u << usable) - 1u;
        const std::size_t need = set.samples - done.accepted;
        int got = std::popcount(keep);
        if (static_cast<std::size_t>(got) >= need) {
            keep = lowest_bits(keep, static_cast<int>(need));
            got = static_cast<int>(need);
            done.attempts += static_cast<std::size_t>(32 - std::countl_zero(keep));
        } else {
            done.attempts += usable;
        }
        commit_scalar(block, keep, done.accepted, set);
        done.accepted += static_cast<std::size_t>(got);
    }
    return done;
}

}  // namespace

SampleCount sample_triangles_fast(const PackedPoint* points, std::uint32_t count,
                                  std::uint64_t seed, std::size_t max_attempts, float min_heron,
                                  SimdLevel simd, TriangleSet& set) {
    SampleCount done;
    switch (simd) {
        case SimdLevel::kAvx512:
            done = sample_triangles_avx512(points, count, seed, max_attempts, min_heron, set);
            break;
        case SimdLevel::kAvx2:
            done = sample_triangles_avx2(points, count, seed, max_attempts, min_heron, set);
            break;
        case SimdLevel::kPortable:
            done = sample_portable(points, count, seed, max_attempts, min_heron, set);
            break;
    }
    // The angles, from the side lengths, in a pass of their own: its iterations are independent,
    // whereas each block of the sampler waits on the previous one's count of accepted triples.
    std::size_t t = 0;
    if (simd == SimdLevel::kAvx512) t = angle_bins_avx512(set, done.accepted);
    if (simd == SimdLevel::kAvx2) t = angle_bins_avx2(set, done.accepted);
    for (; t < done.accepted; ++t)
        set.angle_bins[t] =
            triangle_angle_bins(set.d2[t], set.d2[set.samples + t], set.d2[2 * set.samples + t]);
    return done;
}

}  // namespace esf::detail
