#include "descriptors/esf/esf_points.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "descriptors/esf/esf_point_kernels.hpp"

namespace esf::detail {
namespace {

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
