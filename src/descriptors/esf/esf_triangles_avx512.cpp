// The AVX-512 kernels of the triangle sampler and of the angle pass (see esf_triangles.hpp).

#include <immintrin.h>

#include <algorithm>
#include <bit>

#include "core/simd.hpp"
#include "descriptors/esf/esf_triangle_kernels.hpp"

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Vectors passed between this file's internal functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace esf::detail {

namespace {

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
ESF_TARGET_AVX512 void angle_bins16(TriangleSet& set, std::size_t t) {
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

/// The x, y, z and cell of points[index[l]] for the 16 lanes: each point by one 16-byte load,
/// four points to a vector (lane q of vector j: point 4q + j), then a 4x4 transpose within the
/// 128-bit lanes. Gathers move about one element per cycle; these loads and shuffles take less
/// than half the time of gathering the two 8-byte halves of each point (bench/gather_bench.cpp).
ESF_TARGET_AVX512 inline void load_points16(const PackedPoint* points, __m512i index, __m512& x,
                                            __m512& y, __m512& z, __m512i& cell) {
    alignas(64) std::uint32_t at[kLanes];
    _mm512_store_si512(at, index);
    const auto point = [&](int lane) ESF_TARGET_AVX512 { return _mm_load_ps(&points[at[lane]].x); };
    __m512 rows[4];
    for (int j = 0; j < 4; ++j) {
        __m512 v = _mm512_castps128_ps512(point(j));
        v = _mm512_insertf32x4(v, point(4 + j), 1);
        v = _mm512_insertf32x4(v, point(8 + j), 2);
        rows[j] = _mm512_insertf32x4(v, point(12 + j), 3);
    }
    const __m512 xy01 = _mm512_unpacklo_ps(rows[0], rows[1]);  // x0 x1 y0 y1 per 128-bit lane
    const __m512 zc01 = _mm512_unpackhi_ps(rows[0], rows[1]);  // z0 z1 c0 c1
    const __m512 xy23 = _mm512_unpacklo_ps(rows[2], rows[3]);
    const __m512 zc23 = _mm512_unpackhi_ps(rows[2], rows[3]);
    const auto low = [](__m512 a, __m512 b) ESF_TARGET_AVX512 {
        return _mm512_castpd_ps(_mm512_unpacklo_pd(_mm512_castps_pd(a), _mm512_castps_pd(b)));
    };
    const auto high = [](__m512 a, __m512 b) ESF_TARGET_AVX512 {
        return _mm512_castpd_ps(_mm512_unpackhi_pd(_mm512_castps_pd(a), _mm512_castps_pd(b)));
    };
    x = low(xy01, xy23);
    y = high(xy01, xy23);
    z = low(zc01, zc23);
    cell = _mm512_castps_si512(high(zc01, zc23));
}

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
    // chain of dependent steps (loads, square roots, Heron's product) then overlaps the
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
    const auto draw = [&]() ESF_TARGET_AVX512 {
        Drawn d;
        d.i1 = bounded16(next16(s0, s1, s2, s3), n);
        d.i2 = bounded16(next16(s0, s1, s2, s3), n);
        d.i3 = bounded16(next16(s0, s1, s2, s3), n);
        load_points16(points, d.i1, d.x1, d.y1, d.z1, d.c1);
        load_points16(points, d.i2, d.x2, d.y2, d.z2, d.c2);
        load_points16(points, d.i3, d.x3, d.y3, d.z3, d.c3);
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

}  // namespace

ESF_TARGET_AVX512 SampleCount sample_triangles_avx512(const PackedPoint* points,
                                                      std::uint32_t count, std::uint64_t seed,
                                                      std::size_t max_attempts, float min_heron,
                                                      TriangleSet& set) {
    return sample_avx512(points, count, seed, max_attempts, min_heron, set);
}

ESF_TARGET_AVX512 std::size_t angle_bins_avx512(TriangleSet& set, std::size_t count) {
    std::size_t t = 0;
    for (; t + kLanes <= count; t += kLanes) angle_bins16(set, t);
    return t;
}

}  // namespace esf::detail
