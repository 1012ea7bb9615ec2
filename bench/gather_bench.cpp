// What the AVX-512 kernels of ESF are built around: the cost of a gather on this CPU.
// - Cube look-ups: a 32-bit gather of 16 lanes against a 64-bit gather of 8 (one 3x3x3 cube of
//   27 bits per lane against a 4x4x4 cube of 64 bits), over a table of 4 KB (L1) or 1 MB (the
//   cube table's size).
// - Points of the sampler: 16 packed points (x, y, z, cell) by four 64-bit gathers against 16
//   loads of 16 bytes and a transpose within the 128-bit lanes.
// Each iteration is one look-up of 16 (or 8) lanes; the figure is ns per iteration.
//
// usage: build/bench/gather_bench [--benchmark_filter=REGEX]   (needs AVX-512; skips otherwise)

#include <benchmark/benchmark.h>
#include <immintrin.h>

#include <cstdint>
#include <vector>

#include "core/simd.hpp"

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Vectors passed between this file's internal functions (same target, never exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace {

constexpr int kTableInts = 1 << 18;  // 1 MB, the cube table
constexpr int kPoints = 4096;

struct alignas(16) Point {
    float x, y, z;
    std::uint32_t cell;
};

std::vector<std::int32_t> table() {
    std::vector<std::int32_t> t(kTableInts);
    for (std::size_t i = 0; i < t.size(); ++i) t[i] = static_cast<std::int32_t>(i * 2654435761u);
    return t;
}

/// The next 16 indices below `span` (a power of two): a fixed odd stride, lanes apart.
ESF_TARGET_AVX512 inline __m512i next_indices(__m512i index, int span) {
    return _mm512_and_si512(_mm512_add_epi32(index, _mm512_set1_epi32(40503)),
                            _mm512_set1_epi32(span - 1));
}

ESF_TARGET_AVX512 __m512i first_indices() {
    return _mm512_setr_epi32(0, 17, 33, 51, 68, 85, 101, 119, 135, 153, 170, 187, 204, 221, 238,
                             255);
}

ESF_TARGET_AVX512 void gather32(benchmark::State& state, const std::vector<std::int32_t>& t,
                                int span) {
    __m512i index = first_indices(), sum = _mm512_setzero_si512();
    for (auto _ : state) {
        index = next_indices(index, span);
        sum = _mm512_add_epi32(sum, _mm512_i32gather_epi32(index, t.data(), 4));
    }
    benchmark::DoNotOptimize(_mm512_reduce_add_epi32(sum));
}

ESF_TARGET_AVX512 void gather64(benchmark::State& state, const std::vector<std::int32_t>& t,
                                int span) {
    __m512i index = first_indices(), sum = _mm512_setzero_si512();
    const auto* base = reinterpret_cast<const long long*>(t.data());
    for (auto _ : state) {
        index = next_indices(index, span / 2);
        sum = _mm512_add_epi64(sum, _mm512_i32gather_epi64(_mm512_castsi512_si256(index), base, 8));
    }
    benchmark::DoNotOptimize(_mm512_reduce_add_epi64(sum));
}

void BM_CubeGather32x16(benchmark::State& state) {
    if (!esf::detail::avx512_available()) return state.SkipWithError("no AVX-512");
    const auto t = table();
    gather32(state, t, static_cast<int>(state.range(0)));
}
BENCHMARK(BM_CubeGather32x16)->Arg(1 << 10)->Arg(kTableInts);

void BM_CubeGather64x8(benchmark::State& state) {
    if (!esf::detail::avx512_available()) return state.SkipWithError("no AVX-512");
    const auto t = table();
    gather64(state, t, static_cast<int>(state.range(0)));
}
BENCHMARK(BM_CubeGather64x8)->Arg(1 << 10)->Arg(kTableInts);

std::vector<Point> points() {
    std::vector<Point> p(kPoints);
    for (int i = 0; i < kPoints; ++i)
        p[static_cast<std::size_t>(i)] = {static_cast<float>(i), static_cast<float>(2 * i),
                                          static_cast<float>(3 * i), static_cast<std::uint32_t>(i)};
    return p;
}

ESF_TARGET_AVX512 void points_by_gathers(benchmark::State& state, const std::vector<Point>& p) {
    __m512i index = first_indices();
    __m512 sum = _mm512_setzero_ps();
    const auto* base = reinterpret_cast<const long long*>(p.data());
    const __m512i even =
        _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
    const __m512i odd = _mm512_add_epi32(even, _mm512_set1_epi32(1));
    for (auto _ : state) {
        index = next_indices(index, kPoints);
        const __m512i at = _mm512_slli_epi32(index, 1);
        const __m256i low = _mm512_castsi512_si256(at), high = _mm512_extracti64x4_epi64(at, 1);
        const __m512i xy0 = _mm512_i32gather_epi64(low, base, 8);
        const __m512i xy1 = _mm512_i32gather_epi64(high, base, 8);
        const __m512i zc0 = _mm512_i32gather_epi64(low, base + 1, 8);
        const __m512i zc1 = _mm512_i32gather_epi64(high, base + 1, 8);
        const __m512 x = _mm512_castsi512_ps(_mm512_permutex2var_epi32(xy0, even, xy1));
        const __m512 y = _mm512_castsi512_ps(_mm512_permutex2var_epi32(xy0, odd, xy1));
        const __m512 z = _mm512_castsi512_ps(_mm512_permutex2var_epi32(zc0, even, zc1));
        const __m512 c = _mm512_castsi512_ps(_mm512_permutex2var_epi32(zc0, odd, zc1));
        sum = _mm512_add_ps(sum, _mm512_add_ps(_mm512_add_ps(x, y), _mm512_add_ps(z, c)));
    }
    benchmark::DoNotOptimize(_mm512_reduce_add_ps(sum));
}

ESF_TARGET_AVX512 void points_by_loads(benchmark::State& state, const std::vector<Point>& p) {
    __m512i index = first_indices();
    __m512 sum = _mm512_setzero_ps();
    alignas(64) std::uint32_t at[16];
    for (auto _ : state) {
        index = next_indices(index, kPoints);
        _mm512_store_si512(at, index);
        __m512 rows[4];
        for (int j = 0; j < 4; ++j) {
            __m512 v = _mm512_castps128_ps512(_mm_load_ps(&p[at[j]].x));
            v = _mm512_insertf32x4(v, _mm_load_ps(&p[at[4 + j]].x), 1);
            v = _mm512_insertf32x4(v, _mm_load_ps(&p[at[8 + j]].x), 2);
            rows[j] = _mm512_insertf32x4(v, _mm_load_ps(&p[at[12 + j]].x), 3);
        }
        const __m512 xy01 = _mm512_unpacklo_ps(rows[0], rows[1]);
        const __m512 zc01 = _mm512_unpackhi_ps(rows[0], rows[1]);
        const __m512 xy23 = _mm512_unpacklo_ps(rows[2], rows[3]);
        const __m512 zc23 = _mm512_unpackhi_ps(rows[2], rows[3]);
        const auto pd = [](__m512 v) ESF_TARGET_AVX512 { return _mm512_castps_pd(v); };
        const __m512 x = _mm512_castpd_ps(_mm512_unpacklo_pd(pd(xy01), pd(xy23)));
        const __m512 y = _mm512_castpd_ps(_mm512_unpackhi_pd(pd(xy01), pd(xy23)));
        const __m512 z = _mm512_castpd_ps(_mm512_unpacklo_pd(pd(zc01), pd(zc23)));
        const __m512 c = _mm512_castpd_ps(_mm512_unpackhi_pd(pd(zc01), pd(zc23)));
        sum = _mm512_add_ps(sum, _mm512_add_ps(_mm512_add_ps(x, y), _mm512_add_ps(z, c)));
    }
    benchmark::DoNotOptimize(_mm512_reduce_add_ps(sum));
}

void BM_PointsByGathers(benchmark::State& state) {
    if (!esf::detail::avx512_available()) return state.SkipWithError("no AVX-512");
    points_by_gathers(state, points());
}
BENCHMARK(BM_PointsByGathers);

void BM_PointsByLoads(benchmark::State& state) {
    if (!esf::detail::avx512_available()) return state.SkipWithError("no AVX-512");
    points_by_loads(state, points());
}
BENCHMARK(BM_PointsByLoads);

}  // namespace

BENCHMARK_MAIN();
