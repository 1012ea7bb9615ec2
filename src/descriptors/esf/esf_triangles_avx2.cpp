// The AVX2 kernels of the triangle sampler and of the angle pass (see esf_triangles.hpp): the
// 16 lanes of a block as two halves of 8 (lanes 8 h .. 8 h + 7).

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <bit>

#include "core/simd.hpp"
#include "descriptors/esf/esf_triangle_kernels.hpp"

// Vectors passed between this file's internal functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace esf::detail {

namespace {

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
ESF_TARGET_AVX2 void angle_bins8(TriangleSet& set, std::size_t t) {
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

}  // namespace

ESF_TARGET_AVX2 SampleCount sample_triangles_avx2(const PackedPoint* points, std::uint32_t count,
                                                  std::uint64_t seed, std::size_t max_attempts,
                                                  float min_heron, TriangleSet& set) {
    return sample_avx2(points, count, seed, max_attempts, min_heron, set);
}

ESF_TARGET_AVX2 std::size_t angle_bins_avx2(TriangleSet& set, std::size_t count) {
    std::size_t t = 0;
    for (; t + kHalf <= count; t += kHalf) angle_bins8(set, t);
    return t;
}

}  // namespace esf::detail
