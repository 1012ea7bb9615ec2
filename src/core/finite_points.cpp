#include "core/finite_points.hpp"

#include <immintrin.h>

#include <bit>
#include <cstdint>

// GCC 12 flags the deliberately undefined registers inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace esf::detail {
namespace {

constexpr int kLanes = 16;

/// The finite points of the first `blocks` x 16 points, in order, to `out` (which has 16 floats of
/// slack after what is kept, or is `p` itself: a block's stores stay within the block, read
/// before them); returns how many. Per block of 16 points (48 floats): the floats
/// that are NaN or infinite, one bit each, folded to one bit per point (bits 3j), spread back
/// to the point's three floats, and the kept floats compressed.
ESF_TARGET_AVX512 std::size_t keep_finite_avx512(const float* p, std::size_t blocks, float* out) {
    constexpr int kNonFinite = 0x01 | 0x08 | 0x10 | 0x80;   // quiet NaN, +inf, -inf, signalling NaN
    constexpr std::uint64_t kFirstFloats = 0x249249249249;  // bit 3j of point j, j < 16
    std::size_t kept = 0;                                   // floats
    for (std::size_t b = 0; b < blocks; ++b) {
        const __m512 v[3] = {_mm512_loadu_ps(p + 48 * b), _mm512_loadu_ps(p + 48 * b + 16),
                             _mm512_loadu_ps(p + 48 * b + 32)};
        std::uint64_t bad = 0;
        for (int k = 0; k < 3; ++k)
            bad |= std::uint64_t{_mm512_fpclass_ps_mask(v[k], kNonFinite)} << (16 * k);
        if (bad == 0) {
            for (int k = 0; k < 3; ++k) _mm512_storeu_ps(out + kept + 16 * k, v[k]);
            kept += 48;
            continue;
        }
        const std::uint64_t bad_points = _pext_u64(bad | bad >> 1 | bad >> 2, kFirstFloats);
        const std::uint64_t keep = _pdep_u64(~bad_points & 0xFFFF, kFirstFloats) * 7;
        for (int k = 0; k < 3; ++k) {
            const auto floats = static_cast<__mmask16>(keep >> (16 * k));
            _mm512_storeu_ps(out + kept, _mm512_maskz_compress_ps(floats, v[k]));
            kept += static_cast<std::size_t>(std::popcount(static_cast<unsigned>(floats)));
        }
    }
    return kept / 3;
}

}  // namespace

std::size_t keep_finite_points(std::span<const Eigen::Vector3f> points, SimdLevel simd,
                               std::vector<Eigen::Vector3f>& finite) {
    const std::size_t n = points.size();
    finite.resize(n + 6);  // + 16 floats of slack for the full-width stores
    const std::size_t blocks = simd == SimdLevel::kAvx512 ? n / kLanes : 0;
    std::size_t kept =
        blocks > 0 ? keep_finite_avx512(points.data()->data(), blocks, finite.data()->data()) : 0;
    for (std::size_t i = blocks * kLanes; i < n; ++i)
        if (points[i].allFinite()) finite[kept++] = points[i];
    finite.resize(kept);
    return n - kept;
}

std::size_t keep_finite_in_place(std::vector<Eigen::Vector3f>& points, SimdLevel simd) {
    const std::size_t n = points.size();
    const std::size_t blocks = simd == SimdLevel::kAvx512 ? n / kLanes : 0;
    std::size_t kept = 0;
    if (blocks > 0) {
        float* p = points.data()->data();
        kept = keep_finite_avx512(p, blocks, p);
    }
    for (std::size_t i = blocks * kLanes; i < n; ++i)
        if (points[i].allFinite()) points[kept++] = points[i];
    points.resize(kept);
    return n - kept;
}

}  // namespace esf::detail
