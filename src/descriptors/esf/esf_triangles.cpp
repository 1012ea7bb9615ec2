#include "descriptors/esf/esf_triangles.hpp"

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <numbers>

#include "core/splitmix64.hpp"
#include "descriptors/esf/esf_simd.hpp"

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Vectors passed between this file's internal AVX-512 and AVX2 functions (same target, never
// exported).
#pragma GCC diagnostic ignored "-Wpsabi"

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

constexpr int kLanes = 16;
// Line and triangle classes of the reference: a line is IN when at most one of its cells is
// empty, OUT when at most 7 are occupied; a triangle is OUT when its three lines hold at most 21
// occupied cells, IN when at most 3 of their cells are empty.
constexpr int kLineOutMaxOccupied = 7;
constexpr int kTriangleOutMaxOccupied = 21;
constexpr int kTriangleInMaxEmpty = 3;
// The counts: four interleaved copies of blocks 0-7 (A3, D3, D2 IN and OUT), lane l counting into
// copy l % 4 so that consecutive increments of one bin do not wait on each other's stores; then
// one joint histogram of the MIXED lines over (D2 bin, ratio bin), whose row and column sums are
// blocks 8 (D2 MIXED) and 9 (ratio). Every line then costs one increment instead of two.
constexpr int kCopies = 4;
constexpr int kCopyBins = 8 * kEsfBins;
constexpr int kJointBase = kCopies * kCopyBins;
constexpr int kCountBins = kJointBase + kEsfBins * kEsfBins;

/// Position of a MIXED line's joint bin, relative to the copy lane l counts into.
constexpr std::uint32_t joint_bin(std::size_t lane, int d2_bin, int ratio_bin) {
    return static_cast<std::uint32_t>(kJointBase - static_cast<int>(lane % kCopies) * kCopyBins +
                                      d2_bin * kEsfBins + ratio_bin);
}

// acos(x) = sqrt(1 - x) * (a0 + a1 x + ... + a7 x^7) on [0, 1] (A&S 4.4.46).
constexpr float kAcos[8] = {1.5707963050f, -0.2145988016f, 0.0889789874f, -0.0501743046f,
                            0.0308918810f, -0.0170881256f, 0.0066700901f, -0.0012624911f};
constexpr float kBinsPerRadian = static_cast<float>(kTopBin / (std::numbers::pi / 2.0));
constexpr float kPi = std::numbers::pi_v<float>;

using detail::splitmix64;

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

/// The lowest `n` set bits of `mask`.
inline std::uint32_t lowest_bits(std::uint32_t mask, int n) {
    for (int excess = std::popcount(mask) - n; excess > 0; --excess)
        mask &= ~(std::uint32_t{1} << (31 - std::countl_zero(mask)));
    return mask;
}

ESF_TARGET_AVX512 inline __m512 dot16(__m512 ax, __m512 ay, __m512 az, __m512 bx, __m512 by,
                                      __m512 bz) {
    return _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(ax, bx), _mm512_mul_ps(ay, by)),
                         _mm512_mul_ps(az, bz));
}

/// xoshiro128++ on all 16 lanes.
ESF_TARGET_AVX512 inline __m512i next16(__m512i& s0, __m512i& s1, __m512i& s2, __m512i& s3) {
    const __m512i result = _mm512_add_epi32(_mm512_rol_epi32(_mm512_add_epi32(s0, s3), 7), s0);
    const __m512i t = _mm512_slli_epi32(s1, 9);
    // The update with three-way xors (0x96: a ^ b ^ c) of the old state.
    const __m512i s1_next = _mm512_ternarylogic_epi32(s1, s2, s0, 0x96);
    const __m512i s3_mixed = _mm512_xor_si512(s3, s1);
    s2 = _mm512_ternarylogic_epi32(s2, s0, t, 0x96);
    s0 = _mm512_xor_si512(s0, s3_mixed);
    s1 = s1_next;
    s3 = _mm512_rol_epi32(s3_mixed, 11);
    return result;
}

ESF_TARGET_AVX512 inline __m512i bounded16(__m512i bits, __m512i n) {
    const __m512i even = _mm512_srli_epi64(_mm512_mul_epu32(bits, n), 32);
    const __m512i odd = _mm512_mul_epu32(_mm512_srli_epi64(bits, 32), n);
    return _mm512_mask_blend_epi32(static_cast<__mmask16>(0xAAAA), even, odd);
}

/// fast_acos() on 16 lanes.
ESF_TARGET_AVX512 inline __m512 acos16(__m512 c) {
    const __m512 x = _mm512_min_ps(c, _mm512_set1_ps(1.0f));
    __m512 p = _mm512_set1_ps(kAcos[7]);
    for (int k = 6; k >= 0; --k) p = _mm512_fmadd_ps(p, x, _mm512_set1_ps(kAcos[k]));
    return _mm512_mul_ps(_mm512_sqrt_ps(_mm512_sub_ps(_mm512_set1_ps(1.0f), x)), p);
}

/// third_angle() on 16 lanes.
ESF_TARGET_AVX512 inline __m512 third_angle16(__m512 angle1, __m512 angle3, __m512 n1, __m512 n3,
                                              __m512 n2) {
    const __m512 zero = _mm512_setzero_ps();
    __m512 angle2 = _mm512_sub_ps(_mm512_sub_ps(_mm512_set1_ps(kPi), angle1), angle3);
    angle2 = _mm512_mask_mov_ps(angle2, _mm512_cmp_ps_mask(n3, zero, _CMP_LT_OQ),
                                _mm512_sub_ps(angle3, angle1));
    angle2 = _mm512_mask_mov_ps(angle2, _mm512_cmp_ps_mask(n1, zero, _CMP_LT_OQ),
                                _mm512_sub_ps(angle1, angle3));
    return _mm512_mask_mov_ps(angle2, _mm512_cmp_ps_mask(n2, zero, _CMP_LT_OQ),
                              _mm512_add_ps(angle1, angle3));
}

ESF_TARGET_AVX512 inline __m512i angle_bin16(__m512 angle) {
    const __m512 t =
        _mm512_add_ps(_mm512_mul_ps(angle, _mm512_set1_ps(kBinsPerRadian)), _mm512_set1_ps(0.5f));
    return _mm512_min_epi32(_mm512_cvttps_epi32(t), _mm512_set1_epi32(kTopBin));
}

/// The A3 bins of triangles t .. t + 15 from their side lengths (triangle_angle_bins()).
ESF_TARGET_AVX512 void angle_bins_avx512(TriangleSet& set, std::size_t t) {
    const std::size_t s = set.samples;
    const __m512 a = _mm512_loadu_ps(&set.d2[t]), b = _mm512_loadu_ps(&set.d2[s + t]);
    const __m512 c = _mm512_loadu_ps(&set.d2[2 * s + t]);
    const __m512 aa = _mm512_mul_ps(a, a), bb = _mm512_mul_ps(b, b), cc = _mm512_mul_ps(c, c);
    const __m512 n1 = _mm512_sub_ps(_mm512_add_ps(aa, bb), cc);
    const __m512 n3 = _mm512_sub_ps(_mm512_add_ps(bb, cc), aa);
    const __m512 n2 = _mm512_sub_ps(_mm512_add_ps(aa, cc), bb);
    const __m512 half_inverse =
        _mm512_div_ps(_mm512_set1_ps(0.5f), _mm512_mul_ps(_mm512_mul_ps(a, b), c));
    const __m512 sign = _mm512_set1_ps(-0.0f);
    const __m512 angle1 =
        acos16(_mm512_mul_ps(_mm512_andnot_ps(sign, n1), _mm512_mul_ps(c, half_inverse)));
    const __m512 angle3 =
        acos16(_mm512_mul_ps(_mm512_andnot_ps(sign, n3), _mm512_mul_ps(a, half_inverse)));
    const __m512 angle2 = third_angle16(angle1, angle3, n1, n3, n2);
    _mm512_storeu_si512(&set.angle_bins[t],
                        _mm512_or_si512(_mm512_or_si512(angle_bin16(angle1),
                                                        _mm512_slli_epi32(angle_bin16(angle3), 8)),
                                        _mm512_slli_epi32(angle_bin16(angle2), 16)));
}

/// angle_bin() on 16 lanes.

/// The x, y, z and cell of points[index[l]] for the 16 lanes, by four gathers.
ESF_TARGET_AVX512 inline void gather16(const PackedPoint* points, __m512i index, __m512& x,
                                       __m512& y, __m512& z, __m512i& cell) {
    // Two 8-byte halves (x, y and z, cell) of each point, 8 points per gather: half the gathered
    // elements of 16 single-float gathers. The halves are then split into lanes.
    const __m512i at = _mm512_slli_epi32(index, 1);  // in units of 8 bytes (a point is 16)
    const __m256i low = _mm512_castsi512_si256(at), high = _mm512_extracti64x4_epi64(at, 1);
    const auto* base = reinterpret_cast<const long long*>(points);
    const __m512i xy0 = _mm512_i32gather_epi64(low, base, 8);
    const __m512i xy1 = _mm512_i32gather_epi64(high, base, 8);
    const __m512i zc0 = _mm512_i32gather_epi64(low, base + 1, 8);
    const __m512i zc1 = _mm512_i32gather_epi64(high, base + 1, 8);
    const __m512i even =
        _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
    const __m512i odd = _mm512_add_epi32(even, _mm512_set1_epi32(1));
    x = _mm512_castsi512_ps(_mm512_permutex2var_epi32(xy0, even, xy1));
    y = _mm512_castsi512_ps(_mm512_permutex2var_epi32(xy0, odd, xy1));
    z = _mm512_castsi512_ps(_mm512_permutex2var_epi32(zc0, even, zc1));
    cell = _mm512_permutex2var_epi32(zc0, odd, zc1);
}

/// Blocks of indices drawn ahead of their gathers by sample_avx512 when the packed points do not
/// fit a core's L2 cache (1 MiB on the AMD EPYC measured, more on the Intel Xeon), their points
/// prefetched meanwhile: a gather from the 200,000 points of a scene otherwise waits on the L3
/// cache (a scene's sampling 6 % faster; 4 blocks ahead beat 2 and 8). Smaller clouds gain
/// nothing from it.
constexpr int kPrefetchBlocks = 4;
constexpr std::size_t kPrefetchFromBytes = std::size_t{1} << 20;

template <bool kPrefetch>
ESF_TARGET_AVX512 SampleCount sample_avx512(const PackedPoint* points, std::uint32_t count,
                                            std::uint64_t seed, std::size_t max_attempts,
                                            float min_heron, TriangleSet& set) {
    Streams streams(seed);
    __m512i s0 = _mm512_load_si512(streams.s[0]), s1 = _mm512_load_si512(streams.s[1]);
    __m512i s2 = _mm512_load_si512(streams.s[2]), s3 = _mm512_load_si512(streams.s[3]);
    const __m512i n = _mm512_set1_epi32(static_cast<int>(count));
    const __m512 half = _mm512_set1_ps(0.5f), heron_min = _mm512_set1_ps(min_heron);
    __m512 max_d2 = _mm512_setzero_ps(), max_d3 = _mm512_setzero_ps();
    const std::size_t samples = set.samples;
    SampleCount done;
    // Blocks go through three stages, each a block ahead of the next: indices and points drawn,
    // then the triangles' shape and acceptance, then the bookkeeping and stores. A block's long
    // chain of dependent steps (gathers, square roots, Heron's product) then overlaps the
    // previous blocks' work instead of holding up the loop.
    struct Drawn {
        __m512i i1, i2, i3, c1, c2, c3;
        __m512 x1, y1, z1, x2, y2, z2, x3, y3, z3;
    };
    struct Shaped {
        __m512i c1, c2, c3;
        __m512 a, b, c, heron;
        __mmask16 keep;
    };
    // Indices drawn ahead (kPrefetch): a ring of kPrefetchBlocks blocks of three index vectors.
    struct Indices {
        __m512i i1, i2, i3;
    };
    const auto draw_indices = [&]() ESF_TARGET_AVX512 {
        Indices d;
        d.i1 = bounded16(next16(s0, s1, s2, s3), n);
        d.i2 = bounded16(next16(s0, s1, s2, s3), n);
        d.i3 = bounded16(next16(s0, s1, s2, s3), n);
        if constexpr (kPrefetch) {
            alignas(64) std::uint32_t at[3][kLanes];
            _mm512_store_si512(at[0], d.i1);
            _mm512_store_si512(at[1], d.i2);
            _mm512_store_si512(at[2], d.i3);
            for (const auto& lanes : at)
                for (const std::uint32_t i : lanes)
                    _mm_prefetch(reinterpret_cast<const char*>(points + i), _MM_HINT_T0);
        }
        return d;
    };
    Indices ahead[kPrefetchBlocks];
    if constexpr (kPrefetch)
        for (auto& block : ahead) block = draw_indices();
    int next_ahead = 0;
    const auto draw = [&]() ESF_TARGET_AVX512 {
        Drawn d;
        if constexpr (kPrefetch) {
            const Indices drawn_before = ahead[next_ahead];
            ahead[next_ahead] = draw_indices();
            next_ahead = (next_ahead + 1) % kPrefetchBlocks;
            d.i1 = drawn_before.i1, d.i2 = drawn_before.i2, d.i3 = drawn_before.i3;
        } else {
            const Indices now = draw_indices();
            d.i1 = now.i1, d.i2 = now.i2, d.i3 = now.i3;
        }
        gather16(points, d.i1, d.x1, d.y1, d.z1, d.c1);
        gather16(points, d.i2, d.x2, d.y2, d.z2, d.c2);
        gather16(points, d.i3, d.x3, d.y3, d.z3, d.c3);
        return d;
    };
    const auto shape = [&](const Drawn& d) ESF_TARGET_AVX512 {
        Shaped t;
        t.c1 = d.c1, t.c2 = d.c2, t.c3 = d.c3;
        const __m512 x21 = _mm512_sub_ps(d.x2, d.x1), y21 = _mm512_sub_ps(d.y2, d.y1),
                     z21 = _mm512_sub_ps(d.z2, d.z1);
        const __m512 x31 = _mm512_sub_ps(d.x3, d.x1), y31 = _mm512_sub_ps(d.y3, d.y1),
                     z31 = _mm512_sub_ps(d.z3, d.z1);
        const __m512 x23 = _mm512_sub_ps(d.x2, d.x3), y23 = _mm512_sub_ps(d.y2, d.y3),
                     z23 = _mm512_sub_ps(d.z2, d.z3);
        t.a = _mm512_sqrt_ps(dot16(x21, y21, z21, x21, y21, z21));
        t.b = _mm512_sqrt_ps(dot16(x31, y31, z31, x31, y31, z31));
        t.c = _mm512_sqrt_ps(dot16(x23, y23, z23, x23, y23, z23));
        const __m512 s = _mm512_mul_ps(_mm512_add_ps(_mm512_add_ps(t.a, t.b), t.c), half);
        t.heron = _mm512_mul_ps(
            _mm512_mul_ps(_mm512_mul_ps(s, _mm512_sub_ps(s, t.a)), _mm512_sub_ps(s, t.b)),
            _mm512_sub_ps(s, t.c));
        t.keep = _mm512_cmp_ps_mask(t.heron, heron_min, _CMP_GT_OQ) &
                 _mm512_cmpneq_epi32_mask(d.i1, d.i2) & _mm512_cmpneq_epi32_mask(d.i1, d.i3) &
                 _mm512_cmpneq_epi32_mask(d.i2, d.i3);
        return t;
    };
    Shaped shaped = shape(draw());
    Drawn drawn = draw();
    while (done.accepted < samples && done.attempts < max_attempts) {
        const Shaped block = shaped;
        shaped = shape(drawn);
        drawn = draw();
        const __m512i c1 = block.c1, c2 = block.c2, c3 = block.c3;
        const __m512 a = block.a, b = block.b, c = block.c, heron = block.heron;
        __mmask16 keep = block.keep;
        const std::size_t usable = std::min<std::size_t>(kLanes, max_attempts - done.attempts);
        if (usable < kLanes) keep &= static_cast<__mmask16>((1u << usable) - 1u);
        const std::size_t need = samples - done.accepted;
        int got = std::popcount(static_cast<unsigned>(keep));
        if (static_cast<std::size_t>(got) >= need) {
            keep = static_cast<__mmask16>(lowest_bits(keep, static_cast<int>(need)));
            got = static_cast<int>(need);
            done.attempts += static_cast<std::size_t>(32 - std::countl_zero(unsigned{keep}));
        } else {
            done.attempts += usable;
        }
        if (got == 0) continue;
        const __m512 d3 = _mm512_sqrt_ps(_mm512_sqrt_ps(heron));
        const std::size_t at = done.accepted;
        const __mmask16 out = static_cast<__mmask16>((1u << got) - 1u);
        // The kept lanes, in order: one compress of the lane numbers, then a permute per array.
        const __m512i order = _mm512_maskz_compress_epi32(
            keep, _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15));
        const auto put = [&](float* dst, __m512 v) ESF_TARGET_AVX512 {
            _mm512_mask_storeu_ps(dst, out, _mm512_permutexvar_ps(order, v));
        };
        put(&set.d2[at], a);
        put(&set.d2[samples + at], b);
        put(&set.d2[2 * samples + at], c);
        put(&set.d3[at], d3);
        const __m512i k1 = _mm512_permutexvar_epi32(order, c1);
        const __m512i k2 = _mm512_permutexvar_epi32(order, c2);
        const __m512i k3 = _mm512_permutexvar_epi32(order, c3);
        _mm512_mask_storeu_epi32(&set.line_start[at], out, k1);
        _mm512_mask_storeu_epi32(&set.line_end[at], out, k2);
        _mm512_mask_storeu_epi32(&set.line_start[samples + at], out, k1);
        _mm512_mask_storeu_epi32(&set.line_end[samples + at], out, k3);
        _mm512_mask_storeu_epi32(&set.line_start[2 * samples + at], out, k2);
        _mm512_mask_storeu_epi32(&set.line_end[2 * samples + at], out, k3);
        max_d2 = _mm512_mask_max_ps(max_d2, keep, max_d2, _mm512_max_ps(_mm512_max_ps(a, b), c));
        max_d3 = _mm512_mask_max_ps(max_d3, keep, max_d3, d3);
        done.accepted += static_cast<std::size_t>(got);
    }
    set.max_d2 = _mm512_reduce_max_ps(max_d2);
    set.max_d3 = _mm512_reduce_max_ps(max_d3);
    return done;
}

// AVX2 kernels: the 16 lanes of a block as two halves of 8 (lanes 8 h .. 8 h + 7).

constexpr int kHalf = 8;

/// Left-packing permutations for 8 lanes: entry m holds, in nibble j, the lane of the j-th set
/// bit of m.
constexpr std::array<std::uint32_t, 256> make_pack_table() {
    std::array<std::uint32_t, 256> table{};
    for (std::uint32_t m = 0; m < 256; ++m) {
        std::uint32_t entry = 0;
        int j = 0;
        for (std::uint32_t l = 0; l < 8; ++l)
            if (m >> l & 1) entry |= l << (4 * j++);
        table[m] = entry;
    }
    return table;
}
constexpr std::array<std::uint32_t, 256> kPackTable = make_pack_table();

ESF_TARGET_AVX2 inline __m256 dot8(__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by,
                                   __m256 bz) {
    return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(ay, by)),
                         _mm256_mul_ps(az, bz));
}

ESF_TARGET_AVX2 inline __m256i rotl8(__m256i v, int r) {
    return _mm256_or_si256(_mm256_slli_epi32(v, r), _mm256_srli_epi32(v, 32 - r));
}

/// xoshiro128++ on 8 lanes.
ESF_TARGET_AVX2 inline __m256i next8(__m256i& s0, __m256i& s1, __m256i& s2, __m256i& s3) {
    const __m256i result = _mm256_add_epi32(rotl8(_mm256_add_epi32(s0, s3), 7), s0);
    const __m256i t = _mm256_slli_epi32(s1, 9);
    s2 = _mm256_xor_si256(s2, s0);
    s3 = _mm256_xor_si256(s3, s1);
    s1 = _mm256_xor_si256(s1, s2);
    s0 = _mm256_xor_si256(s0, s3);
    s2 = _mm256_xor_si256(s2, t);
    s3 = rotl8(s3, 11);
    return result;
}

ESF_TARGET_AVX2 inline __m256i bounded8(__m256i bits, __m256i n) {
    const __m256i even = _mm256_srli_epi64(_mm256_mul_epu32(bits, n), 32);
    const __m256i odd = _mm256_mul_epu32(_mm256_srli_epi64(bits, 32), n);
    return _mm256_blend_epi32(even, odd, 0xAA);
}

/// The x, y, z and cell of points[index[l]] for 8 lanes: one 16-byte load per point and 4x4
/// transposes.
ESF_TARGET_AVX2 inline void gather8(const PackedPoint* points, __m256i index, __m256& x, __m256& y,
                                    __m256& z, __m256i& cell) {
    alignas(32) std::uint32_t at[kHalf];
    _mm256_store_si256(reinterpret_cast<__m256i*>(at), index);
    __m256 r[4];
    for (int j = 0; j < 4; ++j)
        r[j] = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(&points[at[j]].x)),
                                    _mm_load_ps(&points[at[j + 4]].x), 1);
    const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
    const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
    x = _mm256_shuffle_ps(t0, t2, 0x44);
    y = _mm256_shuffle_ps(t0, t2, 0xEE);
    z = _mm256_shuffle_ps(t1, t3, 0x44);
    cell = _mm256_castps_si256(_mm256_shuffle_ps(t1, t3, 0xEE));
}

/// Stores the lanes `perm` picks to dst[0 .. got): full width when `room` (the entries that may
/// be written) allows, else masked.
ESF_TARGET_AVX2 inline void put8(float* dst, __m256i perm, __m256i out, bool full, __m256 v) {
    const __m256 packed = _mm256_permutevar8x32_ps(v, perm);
    if (full)
        _mm256_storeu_ps(dst, packed);
    else
        _mm256_maskstore_ps(dst, out, packed);
}
ESF_TARGET_AVX2 inline void put8(std::uint32_t* dst, __m256i perm, __m256i out, bool full,
                                 __m256i v) {
    const __m256i packed = _mm256_permutevar8x32_epi32(v, perm);
    if (full)
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst), packed);
    else
        _mm256_maskstore_epi32(reinterpret_cast<int*>(dst), out, packed);
}

/// One half block of the AVX2 sampler: the triangles of 8 lanes, before the acceptance count.
struct Half8 {
    __m256 a, b, c, heron;
    __m256i c1, c2, c3;
    std::uint32_t accepted;  // lane mask
};

ESF_TARGET_AVX2 SampleCount sample_avx2(const PackedPoint* points, std::uint32_t count,
                                        std::uint64_t seed, std::size_t max_attempts,
                                        float min_heron, TriangleSet& set) {
    Streams streams(seed);
    __m256i s[2][4];
    for (int h = 0; h < 2; ++h)
        for (int w = 0; w < 4; ++w)
            s[h][w] = _mm256_load_si256(reinterpret_cast<const __m256i*>(streams.s[w] + 8 * h));
    const __m256i n = _mm256_set1_epi32(static_cast<int>(count));
    const __m256 half = _mm256_set1_ps(0.5f), heron_min = _mm256_set1_ps(min_heron);
    const __m256i shifts = _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28);
    const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    __m256 max_d2 = _mm256_setzero_ps(), max_d3 = _mm256_setzero_ps();
    const std::size_t samples = set.samples;
    SampleCount done;
    Half8 block[2];
    while (done.accepted < samples && done.attempts < max_attempts) {
        std::uint32_t keep = 0;
        for (int h = 0; h < 2; ++h) {
            __m256i* st = s[h];
            const __m256i i1 = bounded8(next8(st[0], st[1], st[2], st[3]), n);
            const __m256i i2 = bounded8(next8(st[0], st[1], st[2], st[3]), n);
            const __m256i i3 = bounded8(next8(st[0], st[1], st[2], st[3]), n);
            Half8& b = block[h];
            __m256 x1, y1, z1, x2, y2, z2, x3, y3, z3;
            gather8(points, i1, x1, y1, z1, b.c1);
            gather8(points, i2, x2, y2, z2, b.c2);
            gather8(points, i3, x3, y3, z3, b.c3);
            const __m256 x21 = _mm256_sub_ps(x2, x1), y21 = _mm256_sub_ps(y2, y1),
                         z21 = _mm256_sub_ps(z2, z1);
            const __m256 x31 = _mm256_sub_ps(x3, x1), y31 = _mm256_sub_ps(y3, y1),
                         z31 = _mm256_sub_ps(z3, z1);
            const __m256 x23 = _mm256_sub_ps(x2, x3), y23 = _mm256_sub_ps(y2, y3),
                         z23 = _mm256_sub_ps(z2, z3);
            b.a = _mm256_sqrt_ps(dot8(x21, y21, z21, x21, y21, z21));
            b.b = _mm256_sqrt_ps(dot8(x31, y31, z31, x31, y31, z31));
            b.c = _mm256_sqrt_ps(dot8(x23, y23, z23, x23, y23, z23));
            const __m256 sp = _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(b.a, b.b), b.c), half);
            b.heron = _mm256_mul_ps(
                _mm256_mul_ps(_mm256_mul_ps(sp, _mm256_sub_ps(sp, b.a)), _mm256_sub_ps(sp, b.b)),
                _mm256_sub_ps(sp, b.c));
            const __m256i same = _mm256_or_si256(
                _mm256_or_si256(_mm256_cmpeq_epi32(i1, i2), _mm256_cmpeq_epi32(i1, i3)),
                _mm256_cmpeq_epi32(i2, i3));
            const __m256 good = _mm256_andnot_ps(_mm256_castsi256_ps(same),
                                                 _mm256_cmp_ps(b.heron, heron_min, _CMP_GT_OQ));
            keep |= static_cast<std::uint32_t>(_mm256_movemask_ps(good)) << (8 * h);
        }
        const std::size_t usable = std::min<std::size_t>(kLanes, max_attempts - done.attempts);
        if (usable < kLanes) keep &= (1u << usable) - 1u;
        const std::size_t need = samples - done.accepted;
        int got = std::popcount(keep);
        if (static_cast<std::size_t>(got) >= need) {
            keep = lowest_bits(keep, static_cast<int>(need));
            got = static_cast<int>(need);
            done.attempts += static_cast<std::size_t>(32 - std::countl_zero(keep));
        } else {
            done.attempts += usable;
        }
        if (got == 0) continue;
        for (int h = 0; h < 2; ++h) {
            const std::uint32_t mask = keep >> (8 * h) & 0xFF;
            if (mask == 0) continue;
            const Half8& b = block[h];
            const int lanes = std::popcount(mask);
            const __m256i perm =
                _mm256_srlv_epi32(_mm256_set1_epi32(static_cast<int>(kPackTable[mask])), shifts);
            const __m256i out = _mm256_cmpgt_epi32(_mm256_set1_epi32(lanes), iota);
            const std::size_t at = done.accepted;
            // Full-width stores must not reach into the next line's entries.
            const bool full = at + kHalf <= samples;
            const __m256 d3 = _mm256_sqrt_ps(_mm256_sqrt_ps(b.heron));
            put8(&set.d2[at], perm, out, full, b.a);
            put8(&set.d2[samples + at], perm, out, full, b.b);
            put8(&set.d2[2 * samples + at], perm, out, full, b.c);
            put8(&set.d3[at], perm, out, full, d3);
            put8(&set.line_start[at], perm, out, full, b.c1);
            put8(&set.line_end[at], perm, out, full, b.c2);
            put8(&set.line_start[samples + at], perm, out, full, b.c1);
            put8(&set.line_end[samples + at], perm, out, full, b.c3);
            put8(&set.line_start[2 * samples + at], perm, out, full, b.c2);
            put8(&set.line_end[2 * samples + at], perm, out, full, b.c3);
            // Lanes not kept count as 0, below every kept length.
            const __m256 kept = _mm256_castsi256_ps(
                _mm256_cmpgt_epi32(_mm256_and_si256(_mm256_set1_epi32(static_cast<int>(mask)),
                                                    _mm256_sllv_epi32(_mm256_set1_epi32(1), iota)),
                                   _mm256_setzero_si256()));
            max_d2 = _mm256_max_ps(
                max_d2, _mm256_and_ps(kept, _mm256_max_ps(_mm256_max_ps(b.a, b.b), b.c)));
            max_d3 = _mm256_max_ps(max_d3, _mm256_and_ps(kept, d3));
            done.accepted += static_cast<std::size_t>(lanes);
        }
    }
    alignas(32) float lanes2[kHalf], lanes3[kHalf];
    _mm256_store_ps(lanes2, max_d2);
    _mm256_store_ps(lanes3, max_d3);
    set.max_d2 = *std::max_element(lanes2, lanes2 + kHalf);
    set.max_d3 = *std::max_element(lanes3, lanes3 + kHalf);
    return done;
}

/// fast_acos() on 8 lanes.
ESF_TARGET_AVX2 inline __m256 acos8(__m256 c) {
    const __m256 x = _mm256_min_ps(c, _mm256_set1_ps(1.0f));
    __m256 p = _mm256_set1_ps(kAcos[7]);
    for (int k = 6; k >= 0; --k) p = _mm256_fmadd_ps(p, x, _mm256_set1_ps(kAcos[k]));
    return _mm256_mul_ps(_mm256_sqrt_ps(_mm256_sub_ps(_mm256_set1_ps(1.0f), x)), p);
}

/// third_angle() on 8 lanes.
ESF_TARGET_AVX2 inline __m256 third_angle8(__m256 angle1, __m256 angle3, __m256 n1, __m256 n3,
                                           __m256 n2) {
    const __m256 zero = _mm256_setzero_ps();
    __m256 angle2 = _mm256_sub_ps(_mm256_sub_ps(_mm256_set1_ps(kPi), angle1), angle3);
    angle2 = _mm256_blendv_ps(angle2, _mm256_sub_ps(angle3, angle1),
                              _mm256_cmp_ps(n3, zero, _CMP_LT_OQ));
    angle2 = _mm256_blendv_ps(angle2, _mm256_sub_ps(angle1, angle3),
                              _mm256_cmp_ps(n1, zero, _CMP_LT_OQ));
    return _mm256_blendv_ps(angle2, _mm256_add_ps(angle1, angle3),
                            _mm256_cmp_ps(n2, zero, _CMP_LT_OQ));
}

ESF_TARGET_AVX2 inline __m256i angle_bin8(__m256 angle) {
    const __m256 t =
        _mm256_add_ps(_mm256_mul_ps(angle, _mm256_set1_ps(kBinsPerRadian)), _mm256_set1_ps(0.5f));
    return _mm256_min_epi32(_mm256_cvttps_epi32(t), _mm256_set1_epi32(kTopBin));
}

/// The A3 bins of triangles t .. t + 7 from their side lengths (triangle_angle_bins()).
ESF_TARGET_AVX2 void angle_bins_avx2(TriangleSet& set, std::size_t t) {
    const std::size_t s = set.samples;
    const __m256 a = _mm256_loadu_ps(&set.d2[t]), b = _mm256_loadu_ps(&set.d2[s + t]);
    const __m256 c = _mm256_loadu_ps(&set.d2[2 * s + t]);
    const __m256 aa = _mm256_mul_ps(a, a), bb = _mm256_mul_ps(b, b), cc = _mm256_mul_ps(c, c);
    const __m256 n1 = _mm256_sub_ps(_mm256_add_ps(aa, bb), cc);
    const __m256 n3 = _mm256_sub_ps(_mm256_add_ps(bb, cc), aa);
    const __m256 n2 = _mm256_sub_ps(_mm256_add_ps(aa, cc), bb);
    const __m256 half_inverse =
        _mm256_div_ps(_mm256_set1_ps(0.5f), _mm256_mul_ps(_mm256_mul_ps(a, b), c));
    const __m256 sign = _mm256_set1_ps(-0.0f);
    const __m256 angle1 =
        acos8(_mm256_mul_ps(_mm256_andnot_ps(sign, n1), _mm256_mul_ps(c, half_inverse)));
    const __m256 angle3 =
        acos8(_mm256_mul_ps(_mm256_andnot_ps(sign, n3), _mm256_mul_ps(a, half_inverse)));
    const __m256 angle2 = third_angle8(angle1, angle3, n1, n3, n2);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(&set.angle_bins[t]),
                        _mm256_or_si256(_mm256_or_si256(angle_bin8(angle1),
                                                        _mm256_slli_epi32(angle_bin8(angle3), 8)),
                                        _mm256_slli_epi32(angle_bin8(angle2), 16)));
}

/// 1/v for v = 1 .. 64, rounded to nearest.
constexpr std::array<float, 64> reciprocal_table() {
    std::array<float, 64> table{};
    for (int v = 1; v <= 64; ++v)
        table[static_cast<std::size_t>(v - 1)] = 1.0f / static_cast<float>(v);
    return table;
}
alignas(64) constexpr std::array<float, 64> kReciprocal = reciprocal_table();

/// o / v for whole numbers 0 <= o <= 64 and 1 <= v <= 64, equal to the rounded division without
/// the divider (slow for 16 lanes): the product by the rounded reciprocal y, corrected by its
/// remainder, q + (o - q v) y. A test compares it with division for every such pair.
ESF_TARGET_AVX512 inline __m512 small_ratio16(__m512i o, __m512i v) {
    const __m512i slot = _mm512_sub_epi32(v, _mm512_set1_epi32(1));
    const __m512 y =
        _mm512_mask_blend_ps(_mm512_cmpge_epi32_mask(slot, _mm512_set1_epi32(32)),
                             _mm512_permutex2var_ps(_mm512_load_ps(kReciprocal.data()), slot,
                                                    _mm512_load_ps(kReciprocal.data() + 16)),
                             _mm512_permutex2var_ps(_mm512_load_ps(kReciprocal.data() + 32), slot,
                                                    _mm512_load_ps(kReciprocal.data() + 48)));
    const __m512 a = _mm512_cvtepi32_ps(o), b = _mm512_cvtepi32_ps(v);
    const __m512 q = _mm512_mul_ps(a, y);
    return _mm512_fmadd_ps(_mm512_fnmadd_ps(q, b, a), y, q);
}

/// Histogram positions of 16 triangles, relative to the copy of each lane: bins[slot][lane],
/// slots 0-2 the lines (D2 IN or OUT, or the joint bin of a MIXED line), 3 D3, 4-6 A3 with
/// weights weight[0..2].
struct HistogramBlock {
    alignas(64) std::uint32_t bins[7][kLanes];
    alignas(64) std::uint32_t weight[3][kLanes];
};

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

ESF_TARGET_AVX512 void histogram_block_avx512(const TriangleSet& set, const std::uint32_t* occupied,
                                              const std::uint8_t* visited, std::size_t t,
                                              float d2_scale, float d3_scale,
                                              HistogramBlock& block) {
    const std::size_t s = set.samples;
    const __m512i one = _mm512_set1_epi32(1), top = _mm512_set1_epi32(kTopBin);
    const __m512 half = _mm512_set1_ps(0.5f), top_f = _mm512_set1_ps(static_cast<float>(kTopBin));
    static_assert(kEsfBins == 64 && kLanes % kCopies == 0);
    const __m512i joint_base = _mm512_setr_epi32(
        joint_bin(0, 0, 0), joint_bin(1, 0, 0), joint_bin(2, 0, 0), joint_bin(3, 0, 0),
        joint_bin(4, 0, 0), joint_bin(5, 0, 0), joint_bin(6, 0, 0), joint_bin(7, 0, 0),
        joint_bin(8, 0, 0), joint_bin(9, 0, 0), joint_bin(10, 0, 0), joint_bin(11, 0, 0),
        joint_bin(12, 0, 0), joint_bin(13, 0, 0), joint_bin(14, 0, 0), joint_bin(15, 0, 0));
    __m512i o[3], v[3];
    for (int k = 0; k < 3; ++k) {
        const std::size_t at = static_cast<std::size_t>(k) * s + t;
        o[k] = _mm512_loadu_si512(occupied + at);
        v[k] =
            _mm512_cvtepu8_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(visited + at)));
        const __mmask16 in = _mm512_cmpge_epi32_mask(_mm512_add_epi32(o[k], one), v[k]);
        const __mmask16 out = static_cast<__mmask16>(
            ~in & _mm512_cmple_epi32_mask(o[k], _mm512_set1_epi32(kLineOutMaxOccupied)));
        const __mmask16 mixed = static_cast<__mmask16>(~in & ~out);
        const __m512 d = _mm512_loadu_ps(&set.d2[at]);
        const __m512i bin = _mm512_min_epi32(
            _mm512_cvttps_epi32(_mm512_add_ps(_mm512_mul_ps(d, _mm512_set1_ps(d2_scale)), half)),
            top);
        const __m512i in_or_out =
            _mm512_mask_add_epi32(_mm512_add_epi32(bin, _mm512_set1_epi32(6 * kEsfBins)), out, bin,
                                  _mm512_set1_epi32(7 * kEsfBins));
        const __m512i ratio_bin = _mm512_cvttps_epi32(
            _mm512_add_ps(_mm512_mul_ps(small_ratio16(o[k], v[k]), top_f), half));
        const __m512i joint =
            _mm512_add_epi32(_mm512_add_epi32(joint_base, _mm512_slli_epi32(bin, 6)), ratio_bin);
        _mm512_store_si512(block.bins[k], _mm512_mask_mov_epi32(in_or_out, mixed, joint));
    }
    const __m512i occupied_sum = _mm512_add_epi32(_mm512_add_epi32(o[0], o[1]), o[2]);
    const __m512i visited_sum = _mm512_add_epi32(_mm512_add_epi32(v[0], v[1]), v[2]);
    const __mmask16 out =
        _mm512_cmple_epi32_mask(occupied_sum, _mm512_set1_epi32(kTriangleOutMaxOccupied));
    const __mmask16 in = static_cast<__mmask16>(
        ~out & _mm512_cmple_epi32_mask(_mm512_sub_epi32(visited_sum, occupied_sum),
                                       _mm512_set1_epi32(kTriangleInMaxEmpty)));
    __m512i cls = _mm512_set1_epi32(2 * 64);
    cls = _mm512_mask_mov_epi32(cls, out, _mm512_set1_epi32(64));
    cls = _mm512_mask_mov_epi32(cls, in, _mm512_setzero_si512());
    const __m512 d3 = _mm512_loadu_ps(&set.d3[t]);
    const __m512i d3_bin = _mm512_min_epi32(
        _mm512_cvttps_epi32(_mm512_add_ps(_mm512_mul_ps(d3, _mm512_set1_ps(d3_scale)), half)), top);
    _mm512_store_si512(block.bins[3],
                       _mm512_add_epi32(_mm512_add_epi32(cls, _mm512_set1_epi32(3 * 64)), d3_bin));
    const __m512i angles = _mm512_loadu_si512(&set.angle_bins[t]);
    const __m512i byte = _mm512_set1_epi32(255);
    for (int k = 0; k < 3; ++k)
        _mm512_store_si512(
            block.bins[4 + k],
            _mm512_add_epi32(cls, _mm512_and_si512(_mm512_srli_epi32(angles, 8 * k), byte)));
    _mm512_store_si512(block.weight[0], v[2]);
    _mm512_store_si512(block.weight[1], v[0]);
    _mm512_store_si512(block.weight[2], v[1]);
}

/// histogram_block_avx512() with AVX2: two halves of 8 lanes.
ESF_TARGET_AVX2 void histogram_block_avx2(const TriangleSet& set, const std::uint32_t* occupied,
                                          const std::uint8_t* visited, std::size_t first,
                                          float d2_scale, float d3_scale, HistogramBlock& block) {
    const std::size_t s = set.samples;
    const __m256i one = _mm256_set1_epi32(1), top = _mm256_set1_epi32(kTopBin);
    const __m256 half = _mm256_set1_ps(0.5f), top_f = _mm256_set1_ps(static_cast<float>(kTopBin));
    static_assert(kEsfBins == 64 && kHalf % kCopies == 0);
    const __m256i joint_base = _mm256_setr_epi32(
        joint_bin(0, 0, 0), joint_bin(1, 0, 0), joint_bin(2, 0, 0), joint_bin(3, 0, 0),
        joint_bin(4, 0, 0), joint_bin(5, 0, 0), joint_bin(6, 0, 0), joint_bin(7, 0, 0));
    for (int h = 0; h < 2; ++h) {
        const std::size_t t = first + static_cast<std::size_t>(kHalf * h);
        const int lane = kHalf * h;
        __m256i o[3], v[3];
        for (int k = 0; k < 3; ++k) {
            const std::size_t at = static_cast<std::size_t>(k) * s + t;
            o[k] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(occupied + at));
            v[k] = _mm256_cvtepu8_epi32(
                _mm_loadl_epi64(reinterpret_cast<const __m128i*>(visited + at)));
            // in: o + 1 >= v; out: not in and o <= 7; mixed: neither.
            const __m256i not_in = _mm256_cmpgt_epi32(v[k], _mm256_add_epi32(o[k], one));
            const __m256i out = _mm256_andnot_si256(
                _mm256_cmpgt_epi32(o[k], _mm256_set1_epi32(kLineOutMaxOccupied)), not_in);
            const __m256i mixed = _mm256_andnot_si256(out, not_in);
            const __m256 d = _mm256_loadu_ps(&set.d2[at]);
            const __m256i bin =
                _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_add_ps(
                                     _mm256_mul_ps(d, _mm256_set1_ps(d2_scale)), half)),
                                 top);
            const __m256i in_or_out =
                _mm256_add_epi32(bin, _mm256_blendv_epi8(_mm256_set1_epi32(6 * kEsfBins),
                                                         _mm256_set1_epi32(7 * kEsfBins), out));
            const __m256 ratio = _mm256_div_ps(_mm256_cvtepi32_ps(o[k]), _mm256_cvtepi32_ps(v[k]));
            const __m256i ratio_bin =
                _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(ratio, top_f), half));
            const __m256i joint = _mm256_add_epi32(
                _mm256_add_epi32(joint_base, _mm256_slli_epi32(bin, 6)), ratio_bin);
            _mm256_store_si256(reinterpret_cast<__m256i*>(block.bins[k] + lane),
                               _mm256_blendv_epi8(in_or_out, joint, mixed));
        }
        const __m256i occupied_sum = _mm256_add_epi32(_mm256_add_epi32(o[0], o[1]), o[2]);
        const __m256i visited_sum = _mm256_add_epi32(_mm256_add_epi32(v[0], v[1]), v[2]);
        // out: occupied_sum <= 21; in: not out and visited_sum - occupied_sum <= 3.
        const __m256i not_out =
            _mm256_cmpgt_epi32(occupied_sum, _mm256_set1_epi32(kTriangleOutMaxOccupied));
        const __m256i in =
            _mm256_andnot_si256(_mm256_cmpgt_epi32(_mm256_sub_epi32(visited_sum, occupied_sum),
                                                   _mm256_set1_epi32(kTriangleInMaxEmpty)),
                                not_out);
        __m256i cls = _mm256_blendv_epi8(_mm256_set1_epi32(64), _mm256_set1_epi32(2 * 64), not_out);
        cls = _mm256_andnot_si256(in, cls);
        const __m256 d3 = _mm256_loadu_ps(&set.d3[t]);
        const __m256i d3_bin = _mm256_min_epi32(
            _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(d3, _mm256_set1_ps(d3_scale)), half)),
            top);
        _mm256_store_si256(
            reinterpret_cast<__m256i*>(block.bins[3] + lane),
            _mm256_add_epi32(_mm256_add_epi32(cls, _mm256_set1_epi32(3 * 64)), d3_bin));
        const __m256i angles =
            _mm256_loadu_si256(reinterpret_cast<const __m256i*>(&set.angle_bins[t]));
        const __m256i byte = _mm256_set1_epi32(255);
        for (int k = 0; k < 3; ++k)
            _mm256_store_si256(
                reinterpret_cast<__m256i*>(block.bins[4 + k] + lane),
                _mm256_add_epi32(cls, _mm256_and_si256(_mm256_srli_epi32(angles, 8 * k), byte)));
        _mm256_store_si256(reinterpret_cast<__m256i*>(block.weight[0] + lane), v[2]);
        _mm256_store_si256(reinterpret_cast<__m256i*>(block.weight[1] + lane), v[0]);
        _mm256_store_si256(reinterpret_cast<__m256i*>(block.weight[2] + lane), v[1]);
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
            done = count * sizeof(PackedPoint) >= kPrefetchFromBytes
                       ? sample_avx512<true>(points, count, seed, max_attempts, min_heron, set)
                       : sample_avx512<false>(points, count, seed, max_attempts, min_heron, set);
            break;
        case SimdLevel::kAvx2:
            done = sample_avx2(points, count, seed, max_attempts, min_heron, set);
            break;
        case SimdLevel::kPortable:
            done = sample_portable(points, count, seed, max_attempts, min_heron, set);
            break;
    }
    // The angles, from the side lengths, in a pass of their own: its iterations are independent,
    // whereas each block of the sampler waits on the previous one's count of accepted triples.
    std::size_t t = 0;
    if (simd == SimdLevel::kAvx512)
        for (; t + kLanes <= done.accepted; t += kLanes) angle_bins_avx512(set, t);
    if (simd == SimdLevel::kAvx2)
        for (; t + kHalf <= done.accepted; t += kHalf) angle_bins_avx2(set, t);
    for (; t < done.accepted; ++t)
        set.angle_bins[t] =
            triangle_angle_bins(set.d2[t], set.d2[set.samples + t], set.d2[2 * set.samples + t]);
    return done;
}

ESF_TARGET_AVX512 void small_ratios_avx512(const std::uint32_t* o, const std::uint32_t* v,
                                           float* out, std::size_t count) {
    for (std::size_t i = 0; i < count; i += kLanes) {
        const auto live = static_cast<__mmask16>(
            count - i >= kLanes ? 0xffffu : (1u << static_cast<unsigned>(count - i)) - 1u);
        const __m512i occupied = _mm512_maskz_loadu_epi32(live, o + i);
        const __m512i visited =
            _mm512_mask_loadu_epi32(_mm512_set1_epi32(1), live, v + i);  // 1: no lookup past 64
        _mm512_mask_storeu_ps(out + i, live, small_ratio16(occupied, visited));
    }
}

EsfCounts histogram_triangles(const TriangleSet& set, const std::uint32_t* occupied,
                              const std::uint8_t* visited, bool pcl_division, SimdLevel simd) {
    std::array<std::uint32_t, kCountBins> tally{};  // see kCopies
    // The fast sampler multiplies by the reciprocal of the maximum (a last-bit difference at a
    // bin border, far below the sampling noise).
    const float d2_scale = static_cast<float>(kTopBin) / set.max_d2;
    const float d3_scale = static_cast<float>(kTopBin) / set.max_d3;
    const SimdLevel vector = pcl_division ? SimdLevel::kPortable : simd;
    HistogramBlock block;
    for (std::size_t first = 0; first < set.samples; first += kLanes) {
        const std::size_t lanes = std::min<std::size_t>(kLanes, set.samples - first);
        if (vector == SimdLevel::kAvx512 && lanes == kLanes)
            histogram_block_avx512(set, occupied, visited, first, d2_scale, d3_scale, block);
        else if (vector == SimdLevel::kAvx2 && lanes == kLanes)
            histogram_block_avx2(set, occupied, visited, first, d2_scale, d3_scale, block);
        else
            histogram_block_scalar(set, occupied, visited, first, lanes, pcl_division, d2_scale,
                                   d3_scale, block);
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
