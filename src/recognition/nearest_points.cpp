// The nearest point within a radius by a uniform grid (recognition/nearest_points.hpp).

#include "recognition/nearest_points.hpp"

#include <emmintrin.h>  // SSE2, part of every x86-64 CPU

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace esf::detail {

namespace {

// Cells a grid may have: at least this many, and at most kCellsPerPoint a point beyond.
constexpr double kMinCells = 4096.0;
constexpr double kCellsPerPoint = 8.0;
// The query's reach is widened by this share so that no point a float distance would accept
// lies outside the cells read (the distance's rounding is far smaller).
constexpr double kReachSlack = 1e-6;

// The squared distance in float, summed x, then y, then z (as the four lanes of a scan sum it).
inline float squared_distance(float qx, float qy, float qz, float px, float py, float pz) {
    const float dx = qx - px, dy = qy - py, dz = qz - pz;
    float d = dx * dx;
    d += dy * dy;
    d += dz * dz;
    return d;
}

}  // namespace

NearestPoints::NearestPoints(Points points, float cell) : points_(std::move(points)) {
    if (!(cell > 0.0f) || !std::isfinite(cell))
        throw std::invalid_argument("nearest points: cell size must be positive and finite, got " +
                                    std::to_string(cell));
    if (points_.size() >= std::numeric_limits<std::uint32_t>::max())
        throw std::invalid_argument("nearest points: too many points (" +
                                    std::to_string(points_.size()) + ")");
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    std::size_t finite = 0;
    for (const Eigen::Vector3f& p : points_) {
        if (!p.allFinite()) continue;
        lo = lo.cwiseMin(p.cast<double>());
        hi = hi.cwiseMax(p.cast<double>());
        ++finite;
    }
    cell_start_.assign(1, 0);
    if (finite == 0) return;
    origin_ = lo.cast<float>();  // exact: lo holds floats
    const Eigen::Vector3d extent = hi - lo;
    const double max_cells = std::max(kMinCells, kCellsPerPoint * static_cast<double>(finite));
    double size = cell;
    const auto cells_of = [&](double s) {
        return (std::floor(extent.x() / s) + 1.0) * (std::floor(extent.y() / s) + 1.0) *
               (std::floor(extent.z() / s) + 1.0);
    };
    while (cells_of(size) > max_cells) size *= 1.25;
    inverse_cell_ = static_cast<float>(1.0 / size);
    for (int a = 0; a < 3; ++a)
        cells_[a] = static_cast<int>(std::floor(extent[a] * inverse_cell_)) + 1;
    const std::size_t count = static_cast<std::size_t>(cells_[0]) *
                              static_cast<std::size_t>(cells_[1]) *
                              static_cast<std::size_t>(cells_[2]);

    // Counting sort by cell.
    std::vector<std::uint32_t> cell_of(points_.size(), 0);
    cell_start_.assign(count + 1, 0);
    for (std::size_t i = 0; i < points_.size(); ++i) {
        const Eigen::Vector3f& p = points_[i];
        if (!p.allFinite()) continue;
        std::size_t c[3];
        for (int a = 0; a < 3; ++a) {
            // Truncation is the floor: the point is at or above the origin.
            const double at = (static_cast<double>(p[a]) - origin_[a]) * inverse_cell_;
            c[a] = static_cast<std::size_t>(std::clamp(at, 0.0, cells_[a] - 1.0));
        }
        cell_of[i] =
            static_cast<std::uint32_t>((c[2] * static_cast<std::size_t>(cells_[1]) + c[1]) *
                                           static_cast<std::size_t>(cells_[0]) +
                                       c[0]);
        ++cell_start_[cell_of[i] + 1];
    }
    for (std::size_t c = 0; c < count; ++c) cell_start_[c + 1] += cell_start_[c];
    for (std::vector<float>* axis : {&xs_, &ys_, &zs_}) axis->assign(finite + kPadding, 0.0f);
    sorted_index_.resize(finite);
    std::vector<std::uint32_t> next(cell_start_.begin(), cell_start_.end() - 1);
    for (std::size_t i = 0; i < points_.size(); ++i) {
        const Eigen::Vector3f& p = points_[i];
        if (!p.allFinite()) continue;
        const std::uint32_t at = next[cell_of[i]]++;
        xs_[at] = p.x();
        ys_[at] = p.y();
        zs_[at] = p.z();
        sorted_index_[at] = static_cast<std::uint32_t>(i);
    }
}

bool NearestPoints::nearest_within(const Eigen::Vector3f& q, float radius_squared, std::size_t hint,
                                   std::size_t& index, float& squared) const {
    // The next float up, so that a point at exactly the radius counts (std::nextafter for a
    // positive finite bound, without the call).
    float best = radius_squared < std::numeric_limits<float>::infinity()
                     ? std::bit_cast<float>(std::bit_cast<std::uint32_t>(radius_squared) + 1u)
                     : radius_squared;
    bool found = false;
    std::size_t best_index = 0;
    const float qx = q.x(), qy = q.y(), qz = q.z();
    if (hint < points_.size()) {
        const Eigen::Vector3f& h = points_[hint];
        const float d = squared_distance(qx, qy, qz, h.x(), h.y(), h.z());
        if (d < best) {
            best = d;
            best_index = hint;
            found = true;
        }
    }
    // The sorted points [from, to), four at a time: each lane's distance is summed as
    // squared_distance sums it, and lanes nearer than the best so far are taken in order, so
    // that the result is the one a point-by-point loop gives.
    const __m128 qx4 = _mm_set1_ps(qx), qy4 = _mm_set1_ps(qy), qz4 = _mm_set1_ps(qz);
    const auto scan = [&](std::size_t from, std::size_t to) {
        for (std::size_t i = from; i < to; i += 4) {
            const __m128 dx = _mm_sub_ps(qx4, _mm_loadu_ps(xs_.data() + i));
            const __m128 dy = _mm_sub_ps(qy4, _mm_loadu_ps(ys_.data() + i));
            const __m128 dz = _mm_sub_ps(qz4, _mm_loadu_ps(zs_.data() + i));
            __m128 d = _mm_mul_ps(dx, dx);
            d = _mm_add_ps(d, _mm_mul_ps(dy, dy));
            d = _mm_add_ps(d, _mm_mul_ps(dz, dz));
            int nearer = _mm_movemask_ps(_mm_cmplt_ps(d, _mm_set1_ps(best)));
            if (to - i < 4) nearer &= (1 << (to - i)) - 1;
            if (nearer == 0) continue;
            alignas(16) float lanes[4];
            _mm_store_ps(lanes, d);
            for (int lane = 0; lane < 4; ++lane)
                if ((nearer >> lane & 1) && lanes[lane] < best) {
                    best = lanes[lane];
                    best_index = sorted_index_[i + static_cast<std::size_t>(lane)];
                    found = true;
                }
        }
    };
    if (!sorted_index_.empty() && q.allFinite() && best > 0.0f) {
        // The query in cell units: a point of cell k has k <= coordinate < k + 1.
        double at[3];
        for (int a = 0; a < 3; ++a)
            at[a] = (static_cast<double>(q[a]) - origin_[a]) * static_cast<double>(inverse_cell_);
        // The query's own cell first: a near point there narrows the cells read after.
        long own[3] = {-1, -1, -1};  // none when the query lies outside the grid
        if (at[0] >= 0.0 && at[1] >= 0.0 && at[2] >= 0.0 && at[0] < cells_[0] &&
            at[1] < cells_[1] && at[2] < cells_[2]) {
            for (int a = 0; a < 3; ++a) own[a] = static_cast<long>(at[a]);  // the floor here
            const auto cell =
                static_cast<std::size_t>((own[2] * cells_[1] + own[1]) * cells_[0] + own[0]);
            scan(cell_start_[cell], cell_start_[cell + 1]);
        }
        // Then every row of cells within the reach left, but the own cell (read already).
        const double reach = std::sqrt(static_cast<double>(best)) * (1.0 + kReachSlack) *
                             static_cast<double>(inverse_cell_);
        long first[3], last[3];
        bool misses = false;  // the reach misses the grid on some axis
        for (int a = 0; a < 3; ++a) {
            const double from = at[a] - reach, to = at[a] + reach;
            misses = to < 0.0 || from >= cells_[a];
            if (misses) break;
            // Truncation is the floor here: both are clamped to zero or more.
            first[a] = static_cast<long>(std::max(from, 0.0));
            last[a] = static_cast<long>(std::min(to, cells_[a] - 1.0));
        }
        if (!misses) {
            const long nx = cells_[0], ny = cells_[1];
            const auto cells = [&](long from, long to) {  // the row's cells [from, to)
                scan(cell_start_[static_cast<std::size_t>(from)],
                     cell_start_[static_cast<std::size_t>(to)]);
            };
            for (long z = first[2]; z <= last[2]; ++z)
                for (long y = first[1]; y <= last[1]; ++y) {
                    const long row = (z * ny + y) * nx;
                    if (z == own[2] && y == own[1]) {
                        cells(row + first[0], row + own[0]);
                        cells(row + own[0] + 1, row + last[0] + 1);
                    } else {
                        cells(row + first[0], row + last[0] + 1);
                    }
                }
        }
    }
    if (!found) return false;
    index = best_index;
    squared = best;
    return true;
}

}  // namespace esf::detail
