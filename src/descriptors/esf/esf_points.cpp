#include "descriptors/esf/esf_points.hpp"

#include <immintrin.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>

#include "descriptors/esf/esf_simd.hpp"

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Vectors passed between this file's internal AVX-512 and AVX2 functions (same target, never
// exported).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace esf::detail {
namespace {

constexpr int kLanes = 16;

/// `Count` lane-wise partial sums: point i adds to lane i % 16; totals reduce in lane order.
template <int Count>
struct LaneSumsOf {
    double v[Count][kLanes] = {};
    double total(int k) const {
        double sum = 0.0;
        for (double x : v[k]) sum += x;
        return sum;
    }
};

/// Sums of x, y and z.
using LaneSums = LaneSumsOf<3>;
/// Moments of the scaled points: x, y, z, xx, xy, xz, yy, yz, zz.
using LaneMoments = LaneSumsOf<9>;

/// The same moments summed in float (the AVX-512 kernel's first look).
struct FloatMoments {
    alignas(64) float v[9][kLanes] = {};
    double total(int k) const {
        double sum = 0.0;
        for (float x : v[k]) sum += static_cast<double>(x);
        return sum;
    }
};

/// Covariance times count from the totals of moments x, y, z, xx, xy, xz, yy, yz, zz.
template <typename Moments>
Eigen::Matrix3d covariance_of(const Moments& moments, std::size_t n) {
    const double count = static_cast<double>(n);
    const double mean[3] = {moments.total(0) / count, moments.total(1) / count,
                            moments.total(2) / count};
    Eigen::Matrix3d covariance;
    int m = 3;
    for (int k = 0; k < 3; ++k)
        for (int j = k; j < 3; ++j) {
            covariance(k, j) = covariance(j, k) = moments.total(m++) - count * mean[k] * mean[j];
        }
    return covariance;
}

/// Eigenvalues of a covariance, ascending.
Eigen::Vector3d eigenvalues_of(const Eigen::Matrix3d& covariance) {
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly)
        .eigenvalues();
}

/// x, y and z of 16 consecutive points (48 floats).
ESF_TARGET_AVX512 inline void load16(const float* p, __m512& x, __m512& y, __m512& z) {
    const __m512 a = _mm512_loadu_ps(p), b = _mm512_loadu_ps(p + 16), c = _mm512_loadu_ps(p + 32);
    __m512* out[3] = {&x, &y, &z};
    for (int k = 0; k < 3; ++k) {
        alignas(64) int first[kLanes], second[kLanes];
        for (int l = 0; l < kLanes; ++l) {
            const int at = 3 * l + k;
            first[l] = at < 32 ? at : 0;
            second[l] = at < 32 ? l : 16 + at - 32;
        }
        const __m512 ab = _mm512_permutex2var_ps(a, _mm512_load_si512(first), b);
        *out[k] = _mm512_permutex2var_ps(ab, _mm512_load_si512(second), c);
    }
}

/// Lanes 0-7 (which = 0) or 8-15 of a vector.
ESF_TARGET_AVX512 inline __m256 half8(__m512 v, int which) {
    return which == 0 ? _mm512_castps512_ps256(v)
                      : _mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(v), 1));
}

/// Sums of the first `blocks` x 16 points (AVX-512).
ESF_TARGET_AVX512 void sum_avx512(const float* p, std::size_t blocks, LaneSums& sums) {
    __m512d acc[3][2];
    for (int k = 0; k < 3; ++k)
        for (int h = 0; h < 2; ++h) acc[k][h] = _mm512_loadu_pd(sums.v[k] + 8 * h);
    for (std::size_t b = 0; b < blocks; ++b) {
        __m512 v[3];
        load16(p + 48 * b, v[0], v[1], v[2]);
        for (int k = 0; k < 3; ++k) {
            for (int h = 0; h < 2; ++h)
                acc[k][h] = _mm512_add_pd(acc[k][h], _mm512_cvtps_pd(half8(v[k], h)));
        }
    }
    for (int k = 0; k < 3; ++k)
        for (int h = 0; h < 2; ++h) _mm512_storeu_pd(sums.v[k] + 8 * h, acc[k][h]);
}

/// Largest squared distance from the centre of the first `blocks` x 16 points (AVX-512).
ESF_TARGET_AVX512 double radius2_avx512(const float* p, std::size_t blocks,
                                        const Normalisation& t) {
    const __m512d c[3] = {_mm512_set1_pd(t.cx), _mm512_set1_pd(t.cy), _mm512_set1_pd(t.cz)};
    __m512d largest = _mm512_setzero_pd();
    for (std::size_t b = 0; b < blocks; ++b) {
        __m512 v[3];
        load16(p + 48 * b, v[0], v[1], v[2]);
        for (int h = 0; h < 2; ++h) {
            __m512d r = _mm512_setzero_pd();
            for (int k = 0; k < 3; ++k) {
                const __m512d d = _mm512_sub_pd(_mm512_cvtps_pd(half8(v[k], h)), c[k]);
                r = k == 0 ? _mm512_mul_pd(d, d) : _mm512_add_pd(r, _mm512_mul_pd(d, d));
            }
            largest = _mm512_max_pd(largest, r);
        }
    }
    return _mm512_reduce_max_pd(largest);
}

/// The cell of 16 scaled coordinates, as cell_of().
ESF_TARGET_AVX512 inline __m512i cell16(__m512 v, int half) {
    const __m512i truncated = _mm512_cvttps_epi32(v);
    const __mmask16 fractional = _mm512_cmp_ps_mask(_mm512_cvtepi32_ps(truncated), v, _CMP_NEQ_UQ);
    const __mmask16 negative = _mm512_cmp_ps_mask(v, _mm512_setzero_ps(), _CMP_LT_OQ);
    const __m512i one = _mm512_set1_epi32(1);
    // v < 0: truncated - fractional + half; else truncated + fractional + half - 1.
    __m512i c = _mm512_add_epi32(truncated, _mm512_set1_epi32(half));
    c = _mm512_mask_sub_epi32(c, negative & fractional, c, one);
    c = _mm512_mask_sub_epi32(c, static_cast<__mmask16>(~negative & ~fractional), c, one);
    return _mm512_min_epi32(_mm512_max_epi32(c, _mm512_setzero_si512()),
                            _mm512_set1_epi32(2 * half - 1));
}

ESF_TARGET_AVX512 inline __m512 scale16(__m512 v, __m512d centre, __m512d scale) {
    const __m256 lo =
        _mm512_cvtpd_ps(_mm512_mul_pd(_mm512_sub_pd(_mm512_cvtps_pd(half8(v, 0)), centre), scale));
    const __m256 hi =
        _mm512_cvtpd_ps(_mm512_mul_pd(_mm512_sub_pd(_mm512_cvtps_pd(half8(v, 1)), centre), scale));
    return _mm512_insertf32x8(_mm512_castps256_ps512(lo), hi, 1);
}

/// Scales, packs and voxelises the first `blocks` x 16 points (AVX-512); the moments go to
/// `moments`, and to `cells` each cell that differs from the previous point's (a scan's
/// neighbouring points often share a cell: the grid then takes one write per run). Returns how
/// many cells were written (`cells` has room for 16 more than the points).
ESF_TARGET_AVX512 std::size_t voxelise_avx512(const float* p, std::size_t blocks,
                                              const Normalisation& t, int half, PackedPoint* packed,
                                              std::uint32_t* cells, FloatMoments& moments) {
    std::size_t kept = 0;
    __m512i previous = _mm512_set1_epi32(-1);  // no cell: the first point always counts
    __m512 sums[9];
    for (int m = 0; m < 9; ++m) sums[m] = _mm512_load_ps(moments.v[m]);
    const __m512d centre[3] = {_mm512_set1_pd(t.cx), _mm512_set1_pd(t.cy), _mm512_set1_pd(t.cz)};
    const __m512d scale = _mm512_set1_pd(t.scale);
    for (std::size_t b = 0; b < blocks; ++b) {
        __m512 v[3];
        load16(p + 48 * b, v[0], v[1], v[2]);
        for (int k = 0; k < 3; ++k) v[k] = scale16(v[k], centre[k], scale);
        const __m512i cell = _mm512_or_si512(
            _mm512_or_si512(cell16(v[0], half), _mm512_slli_epi32(cell16(v[1], half), 6)),
            _mm512_slli_epi32(cell16(v[2], half), 12));
        // Lane l's predecessor: lane l - 1, or the previous block's last lane.
        const __mmask16 differs =
            _mm512_cmpneq_epi32_mask(cell, _mm512_alignr_epi32(cell, previous, 15));
        previous = cell;
        _mm512_storeu_si512(cells + kept, _mm512_maskz_compress_epi32(differs, cell));
        kept += static_cast<std::size_t>(std::popcount(static_cast<unsigned>(differs)));
        // Back to x, y, z, cell per point: 4x4 transposes within the 128-bit lanes.
        const __m512 w = _mm512_castsi512_ps(cell);
        const __m512 xy_lo = _mm512_unpacklo_ps(v[0], v[1]), xy_hi = _mm512_unpackhi_ps(v[0], v[1]);
        const __m512 zw_lo = _mm512_unpacklo_ps(v[2], w), zw_hi = _mm512_unpackhi_ps(v[2], w);
        const __m512 r[4] = {
            _mm512_castpd_ps(_mm512_unpacklo_pd(_mm512_castps_pd(xy_lo), _mm512_castps_pd(zw_lo))),
            _mm512_castpd_ps(_mm512_unpackhi_pd(_mm512_castps_pd(xy_lo), _mm512_castps_pd(zw_lo))),
            _mm512_castpd_ps(_mm512_unpacklo_pd(_mm512_castps_pd(xy_hi), _mm512_castps_pd(zw_hi))),
            _mm512_castpd_ps(_mm512_unpackhi_pd(_mm512_castps_pd(xy_hi), _mm512_castps_pd(zw_hi)))};
        // r[j] holds points 4q + j in its 128-bit lane q.
        float* out = &packed[kLanes * b].x;
        for (int j = 0; j < 4; ++j) {
            _mm_store_ps(out + 4 * j, _mm512_castps512_ps128(r[j]));
            _mm_store_ps(out + 4 * (4 + j), _mm512_extractf32x4_ps(r[j], 1));
            _mm_store_ps(out + 4 * (8 + j), _mm512_extractf32x4_ps(r[j], 2));
            _mm_store_ps(out + 4 * (12 + j), _mm512_extractf32x4_ps(r[j], 3));
        }
        for (int k = 0; k < 3; ++k) sums[k] = _mm512_add_ps(sums[k], v[k]);
        int m = 3;
        for (int k = 0; k < 3; ++k)
            for (int j = k; j < 3; ++j, ++m) sums[m] = _mm512_fmadd_ps(v[k], v[j], sums[m]);
    }
    for (int m = 0; m < 9; ++m) _mm512_store_ps(moments.v[m], sums[m]);
    return kept;
}

/// The moments in double of the first `count` packed points (lane i % 16), as the portable code
/// sums them.
LaneMoments packed_moments(const PackedPoint* packed, std::size_t count) {
    LaneMoments moments;
    for (std::size_t i = 0; i < count; ++i) {
        const double d[3] = {packed[i].x, packed[i].y, packed[i].z};
        const std::size_t l = i % kLanes;
        for (int k = 0; k < 3; ++k) moments.v[k][l] += d[k];
        int m = 3;
        for (int k = 0; k < 3; ++k)
            for (int j = k; j < 3; ++j) moments.v[m++][l] += d[k] * d[j];
    }
    return moments;
}

// AVX2 kernels: 16 points as two halves of 8, each coordinate as four vectors of 4 doubles.

/// Lanes of the blend of three vectors of 8 floats that hold coordinate K of 8 points.
template <int K>
constexpr int blend_from(int source) {
    int mask = 0;
    for (int j = 0; j < 8; ++j)
        if ((2 * source + j) % 3 == K) mask |= 1 << j;
    return mask;
}

/// Coordinate K of the 8 points in a, b, c (24 floats).
template <int K>
ESF_TARGET_AVX2 inline __m256 coordinate8(__m256 a, __m256 b, __m256 c) {
    const __m256 m = _mm256_blend_ps(_mm256_blend_ps(a, b, blend_from<K>(1)), c, blend_from<K>(2));
    return _mm256_permutevar8x32_ps(
        m, _mm256_setr_epi32(K % 8, (3 + K) % 8, (6 + K) % 8, (9 + K) % 8, (12 + K) % 8,
                             (15 + K) % 8, (18 + K) % 8, (21 + K) % 8));
}

/// x, y and z of 8 consecutive points (24 floats).
ESF_TARGET_AVX2 inline void load8(const float* p, __m256& x, __m256& y, __m256& z) {
    const __m256 a = _mm256_loadu_ps(p), b = _mm256_loadu_ps(p + 8), c = _mm256_loadu_ps(p + 16);
    x = coordinate8<0>(a, b, c);
    y = coordinate8<1>(a, b, c);
    z = coordinate8<2>(a, b, c);
}

/// Lanes 0-3 (which = 0) or 4-7 of a vector, in double.
ESF_TARGET_AVX2 inline __m256d quarter4(__m256 v, int which) {
    return _mm256_cvtps_pd(which == 0 ? _mm256_castps256_ps128(v) : _mm256_extractf128_ps(v, 1));
}

/// Sums of the first `blocks` x 16 points (AVX2).
ESF_TARGET_AVX2 void sum_avx2(const float* p, std::size_t blocks, LaneSums& sums) {
    __m256d acc[3][4];
    for (int k = 0; k < 3; ++k)
        for (int q = 0; q < 4; ++q) acc[k][q] = _mm256_loadu_pd(sums.v[k] + 4 * q);
    for (std::size_t b = 0; b < blocks; ++b) {
        for (int h = 0; h < 2; ++h) {
            __m256 v[3];
            load8(p + 48 * b + 24 * h, v[0], v[1], v[2]);
            for (int k = 0; k < 3; ++k)
                for (int q = 0; q < 2; ++q)
                    acc[k][2 * h + q] = _mm256_add_pd(acc[k][2 * h + q], quarter4(v[k], q));
        }
    }
    for (int k = 0; k < 3; ++k)
        for (int q = 0; q < 4; ++q) _mm256_storeu_pd(sums.v[k] + 4 * q, acc[k][q]);
}

/// Largest squared distance from the centre of the first `blocks` x 16 points (AVX2).
ESF_TARGET_AVX2 double radius2_avx2(const float* p, std::size_t blocks, const Normalisation& t) {
    const __m256d c[3] = {_mm256_set1_pd(t.cx), _mm256_set1_pd(t.cy), _mm256_set1_pd(t.cz)};
    __m256d largest = _mm256_setzero_pd();
    for (std::size_t i = 0; i < 2 * blocks; ++i) {
        __m256 v[3];
        load8(p + 24 * i, v[0], v[1], v[2]);
        for (int q = 0; q < 2; ++q) {
            __m256d r = _mm256_setzero_pd();
            for (int k = 0; k < 3; ++k) {
                const __m256d d = _mm256_sub_pd(quarter4(v[k], q), c[k]);
                r = k == 0 ? _mm256_mul_pd(d, d) : _mm256_add_pd(r, _mm256_mul_pd(d, d));
            }
            largest = _mm256_max_pd(largest, r);
        }
    }
    alignas(32) double lanes[4];
    _mm256_store_pd(lanes, largest);
    return std::max(std::max(lanes[0], lanes[1]), std::max(lanes[2], lanes[3]));
}

/// The cell of 8 scaled coordinates, as cell_of().
ESF_TARGET_AVX2 inline __m256i cell8(__m256 v, int half) {
    const __m256i truncated = _mm256_cvttps_epi32(v);
    const __m256i fractional =
        _mm256_castps_si256(_mm256_cmp_ps(_mm256_cvtepi32_ps(truncated), v, _CMP_NEQ_UQ));
    const __m256i negative = _mm256_castps_si256(_mm256_cmp_ps(v, _mm256_setzero_ps(), _CMP_LT_OQ));
    // v < 0: truncated - fractional + half; else truncated + fractional + half - 1 (the masks
    // are -1 where set).
    __m256i c = _mm256_add_epi32(truncated, _mm256_set1_epi32(half));
    c = _mm256_add_epi32(c, _mm256_and_si256(negative, fractional));
    c = _mm256_add_epi32(
        c, _mm256_andnot_si256(_mm256_or_si256(negative, fractional), _mm256_set1_epi32(-1)));
    return _mm256_min_epi32(_mm256_max_epi32(c, _mm256_setzero_si256()),
                            _mm256_set1_epi32(2 * half - 1));
}

ESF_TARGET_AVX2 inline __m256 scale8(__m256 v, __m256d centre, __m256d scale) {
    const __m128 lo = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(quarter4(v, 0), centre), scale));
    const __m128 hi = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(quarter4(v, 1), centre), scale));
    return _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
}

/// Scales, packs and voxelises the first `blocks` x 16 points (AVX2); their cells go to
/// `cells`, the moments to `moments`.
ESF_TARGET_AVX2 void voxelise_avx2(const float* p, std::size_t blocks, const Normalisation& t,
                                   int half, PackedPoint* packed, std::uint32_t* cells,
                                   LaneMoments& moments) {
    const __m256d centre[3] = {_mm256_set1_pd(t.cx), _mm256_set1_pd(t.cy), _mm256_set1_pd(t.cz)};
    const __m256d scale = _mm256_set1_pd(t.scale);
    for (std::size_t i = 0; i < 2 * blocks; ++i) {
        __m256 v[3];
        load8(p + 24 * i, v[0], v[1], v[2]);
        for (int k = 0; k < 3; ++k) v[k] = scale8(v[k], centre[k], scale);
        const __m256i cell = _mm256_or_si256(
            _mm256_or_si256(cell8(v[0], half), _mm256_slli_epi32(cell8(v[1], half), 6)),
            _mm256_slli_epi32(cell8(v[2], half), 12));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(cells + 8 * i), cell);
        // Back to x, y, z, cell per point: 4x4 transposes within the 128-bit lanes.
        const __m256 w = _mm256_castsi256_ps(cell);
        const __m256 xy_lo = _mm256_unpacklo_ps(v[0], v[1]), xy_hi = _mm256_unpackhi_ps(v[0], v[1]);
        const __m256 zw_lo = _mm256_unpacklo_ps(v[2], w), zw_hi = _mm256_unpackhi_ps(v[2], w);
        const __m256 r[4] = {
            _mm256_castpd_ps(_mm256_unpacklo_pd(_mm256_castps_pd(xy_lo), _mm256_castps_pd(zw_lo))),
            _mm256_castpd_ps(_mm256_unpackhi_pd(_mm256_castps_pd(xy_lo), _mm256_castps_pd(zw_lo))),
            _mm256_castpd_ps(_mm256_unpacklo_pd(_mm256_castps_pd(xy_hi), _mm256_castps_pd(zw_hi))),
            _mm256_castpd_ps(_mm256_unpackhi_pd(_mm256_castps_pd(xy_hi), _mm256_castps_pd(zw_hi)))};
        // r[j] holds points 4q + j in its 128-bit lane q.
        float* out = &packed[8 * i].x;
        for (int j = 0; j < 4; ++j) {
            _mm_store_ps(out + 4 * j, _mm256_castps256_ps128(r[j]));
            _mm_store_ps(out + 4 * (4 + j), _mm256_extractf128_ps(r[j], 1));
        }
        // Points 8 i .. 8 i + 7 go to lanes 8 (i % 2) ...
        const std::size_t lane = 8 * (i % 2);
        for (int k = 0; k < 3; ++k)
            for (int q = 0; q < 2; ++q) {
                double* lanes = moments.v[k] + lane + 4 * q;
                _mm256_storeu_pd(lanes, _mm256_add_pd(_mm256_loadu_pd(lanes), quarter4(v[k], q)));
            }
        int m = 3;
        for (int k = 0; k < 3; ++k)
            for (int j = k; j < 3; ++j) {
                // Products in double, as the portable code forms them.
                double* lanes = moments.v[m++] + lane;
                for (int q = 0; q < 2; ++q) {
                    const __m256d a = quarter4(v[k], q), c = quarter4(v[j], q);
                    _mm256_storeu_pd(lanes + 4 * q, _mm256_add_pd(_mm256_loadu_pd(lanes + 4 * q),
                                                                  _mm256_mul_pd(a, c)));
                }
            }
    }
}

/// Sets cells in the grid. Consecutive points of a scan often fall into one grid word: even and
/// odd points go to two copies of the grid, merged at the end, so that a point's update does not
/// wait for its predecessor's (branches on word changes would mispredict, a single copy would
/// serialise on store forwarding).
void set_cells(const std::uint32_t* cells, std::size_t count, VoxelGrid& grid) {
    // Four runs through the cells at once (each a quarter, in order): neighbouring cells often
    // share a word of the grid, and one run's read-modify-writes of it then do not hold up the
    // others'.
    const std::size_t quarter = count / 4;
    const auto set = [&grid](std::uint32_t cell) {
        grid.words[cell >> 6] |= std::uint64_t{1} << (cell & 63);
    };
    for (std::size_t i = 0; i < quarter; ++i) {
        set(cells[i]);
        set(cells[quarter + i]);
        set(cells[2 * quarter + i]);
        set(cells[3 * quarter + i]);
    }
    for (std::size_t i = 4 * quarter; i < count; ++i) set(cells[i]);
}

}  // namespace

NormaliseOutcome normalise_points(std::span<const Eigen::Vector3f> points, int half, SimdLevel simd,
                                  Normalisation& out) {
    const std::size_t n = points.size();
    const float* p = points.data()->data();
    const std::size_t blocks = simd != SimdLevel::kPortable ? n / kLanes : 0;
    LaneSums sums;
    // In chunks, each adding to the same lane sums (so the sums do not depend on the chunking):
    // a cloud with non-finite points (an organised scan's missing depths) is told apart after
    // its first chunk that holds one, not after a pass over every point.
    constexpr std::size_t kChunkBlocks = 256;
    const auto non_finite = [&sums] {
        for (const auto& lanes : sums.v)
            for (const double x : lanes)
                if (!std::isfinite(x)) return true;
        return false;
    };
    for (std::size_t b = 0; b < blocks; b += kChunkBlocks) {
        const std::size_t chunk = std::min(kChunkBlocks, blocks - b);
        if (simd == SimdLevel::kAvx512)
            sum_avx512(p + 3 * kLanes * b, chunk, sums);
        else
            sum_avx2(p + 3 * kLanes * b, chunk, sums);
        if (non_finite()) return NormaliseOutcome::kNonFinite;
    }
    for (std::size_t i = blocks * kLanes; i < n; ++i) {
        for (int k = 0; k < 3; ++k) sums.v[k][i % kLanes] += points[i][k];
        if (i % (kChunkBlocks * kLanes) == kChunkBlocks * kLanes - 1 && non_finite())
            return NormaliseOutcome::kNonFinite;
    }
    const double count = static_cast<double>(n);
    out.cx = sums.total(0) / count;
    out.cy = sums.total(1) / count;
    out.cz = sums.total(2) / count;
    if (!std::isfinite(out.cx) || !std::isfinite(out.cy) || !std::isfinite(out.cz))
        return NormaliseOutcome::kNonFinite;
    double largest = blocks == 0                  ? 0.0
                     : simd == SimdLevel::kAvx512 ? radius2_avx512(p, blocks, out)
                                                  : radius2_avx2(p, blocks, out);
    for (std::size_t i = blocks * kLanes; i < n; ++i) {
        const double x = static_cast<double>(points[i].x()) - out.cx;
        const double y = static_cast<double>(points[i].y()) - out.cy;
        const double z = static_cast<double>(points[i].z()) - out.cz;
        largest = std::max(largest, x * x + y * y + z * z);
    }
    if (!(largest > 0.0) || !std::isfinite(largest)) return NormaliseOutcome::kCoincident;
    out.scale = half / std::sqrt(largest);
    return NormaliseOutcome::kNormalised;
}

bool on_one_line(const Eigen::Matrix3d& covariance) {
    const Eigen::Vector3d eigenvalues = eigenvalues_of(covariance);  // ascending
    return eigenvalues[1] <= 1e-10 * eigenvalues[2];
}

bool voxelise_points(std::span<const Eigen::Vector3f> points, const Normalisation& t, int half,
                     SimdLevel simd, std::vector<PackedPoint>& packed,
                     std::vector<std::uint32_t>& cells, VoxelGrid& grid) {
    const std::size_t n = points.size();
    packed.resize(n + 1);  // + a readable padding point for 16-byte loads
    packed[n] = {};
    cells.resize(n);
    const std::size_t blocks = simd != SimdLevel::kPortable ? n / kLanes : 0;
    const bool first_look = blocks > 0 && simd == SimdLevel::kAvx512;
    LaneMoments moments;
    FloatMoments float_moments;
    std::size_t kept = blocks * kLanes;  // cells written so far
    if (first_look) {
        cells.resize(n + kLanes);  // + room for full-width stores
        kept = voxelise_avx512(points.data()->data(), blocks, t, half, packed.data(), cells.data(),
                               float_moments);
    } else if (blocks > 0) {
        voxelise_avx2(points.data()->data(), blocks, t, half, packed.data(), cells.data(), moments);
    }
    for (std::size_t i = blocks * kLanes; i < n; ++i) {
        const auto& q = points[i];
        const auto x = static_cast<float>((static_cast<double>(q.x()) - t.cx) * t.scale);
        const auto y = static_cast<float>((static_cast<double>(q.y()) - t.cy) * t.scale);
        const auto z = static_cast<float>((static_cast<double>(q.z()) - t.cz) * t.scale);
        const std::uint32_t cell = pack_cell(cell_of(x, half), cell_of(y, half), cell_of(z, half));
        packed[i] = {x, y, z, cell};
        cells[kept++] = cell;
        const double d[3] = {x, y, z};
        const std::size_t l = i % kLanes;
        int m = 3;
        for (int k = 0; k < 3; ++k) {
            moments.v[k][l] += d[k];
            float_moments.v[k][l] += static_cast<float>(d[k]);
            for (int j = k; j < 3; ++j, ++m) {
                moments.v[m][l] += d[k] * d[j];
                float_moments.v[m][l] += static_cast<float>(d[k] * d[j]);
            }
        }
    }
    set_cells(cells.data(), kept, grid);
    if (!first_look) return on_one_line(covariance_of(moments, n));
    // A sum of at most 2^16 floats per lane errs by at most 2^-8 of the sum of its terms' sizes:
    // the float covariance then lies within 0.05 of the largest eigenvalue of the exact one, and a
    // second eigenvalue of at least a fifth of the largest cannot come from a line.
    constexpr std::size_t kFloatLookMaxPoints = std::size_t{1} << 20;
    if (n <= kFloatLookMaxPoints) {
        const Eigen::Vector3d eigenvalues = eigenvalues_of(covariance_of(float_moments, n));
        if (eigenvalues[2] > 0.0 && eigenvalues[1] >= 0.2 * eigenvalues[2]) return false;
    }
    return on_one_line(covariance_of(packed_moments(packed.data(), n), n));
}

}  // namespace esf::detail
