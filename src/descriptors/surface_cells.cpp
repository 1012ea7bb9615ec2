#include "descriptors/surface_cells.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

namespace esf::detail {
namespace {

/// Point count, sum and the six distinct second moments (about the grid origin) of the points of
/// one cell: ten doubles, added lane by lane.
struct Moments {
    // count, x, y, z, xx, xy, xz, yy, yz, zz
    std::array<double, 10> m{};

    void add_point(const Eigen::Vector3d& q) {
        m[0] += 1.0;
        m[1] += q.x();
        m[2] += q.y();
        m[3] += q.z();
        m[4] += q.x() * q.x();
        m[5] += q.x() * q.y();
        m[6] += q.x() * q.z();
        m[7] += q.y() * q.y();
        m[8] += q.y() * q.z();
        m[9] += q.z() * q.z();
    }
    void add(const Moments& other) {
        for (std::size_t i = 0; i < m.size(); ++i) m[i] += other.m[i];
    }
    double count() const { return m[0]; }
    Eigen::Vector3d sum() const { return {m[1], m[2], m[3]}; }
    Eigen::Matrix3d outer() const {
        Eigen::Matrix3d o;
        o << m[4], m[5], m[6], m[5], m[7], m[8], m[6], m[8], m[9];
        return o;
    }
};

}  // namespace

SurfaceCells surface_cells(std::span<const Eigen::Vector3f> points, double cell_size,
                           const std::string& what) {
    if (!(std::isfinite(cell_size) && cell_size > 0.0))
        throw std::invalid_argument(what + ": cell size must be positive and finite, got " +
                                    std::to_string(cell_size));
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    std::size_t finite = 0;
    for (const Eigen::Vector3f& p : points) {
        if (!p.allFinite()) continue;
        ++finite;
        lo = lo.cwiseMin(p.cast<double>());
        hi = hi.cwiseMax(p.cast<double>());
    }
    if (finite < 3)
        throw std::invalid_argument(what + ": needs at least 3 finite points, got " +
                                    std::to_string(finite));
    const double diagonal = (hi - lo).norm();
    const double h = std::max(cell_size, diagonal / 64.0);
    std::array<int, 3> dims{};
    for (int a = 0; a < 3; ++a)
        dims[static_cast<std::size_t>(a)] = static_cast<int>(std::floor((hi[a] - lo[a]) / h)) + 1;
    const auto cell_key = [&](int x, int y, int z) {
        return (static_cast<std::size_t>(z) * static_cast<std::size_t>(dims[1]) +
                static_cast<std::size_t>(y)) *
                   static_cast<std::size_t>(dims[0]) +
               static_cast<std::size_t>(x);
    };
    // Dense grid of cell numbers (-1: empty), cells in order of first occupation.
    std::vector<std::int32_t> grid(static_cast<std::size_t>(dims[0]) *
                                       static_cast<std::size_t>(dims[1]) *
                                       static_cast<std::size_t>(dims[2]),
                                   -1);
    std::vector<Moments> cells;
    std::vector<std::array<int, 3>> coords;
    for (const Eigen::Vector3f& p : points) {
        if (!p.allFinite()) continue;
        const Eigen::Vector3d q = p.cast<double>() - lo;
        std::array<int, 3> c{};
        for (int a = 0; a < 3; ++a)
            c[static_cast<std::size_t>(a)] =
                std::min(static_cast<int>(q[a] / h), dims[static_cast<std::size_t>(a)] - 1);
        std::int32_t& slot = grid[cell_key(c[0], c[1], c[2])];
        if (slot < 0) {
            slot = static_cast<std::int32_t>(cells.size());
            cells.emplace_back();
            coords.push_back(c);
        }
        cells[static_cast<std::size_t>(slot)].add_point(q);
    }

    // Normals and surface variation per cell, from its 3 x 3 x 3 neighbourhood.
    SurfaceCells out;
    out.cell_size = h;
    out.finite_points = finite;
    std::vector<SurfaceCell>& surfels = out.cells;
    surfels.reserve(cells.size());
    for (std::size_t i = 0; i < cells.size(); ++i) {
        Moments m;
        const auto& c = coords[i];
        for (int dz = -1; dz <= 1; ++dz) {
            const int z = c[2] + dz;
            if (z < 0 || z >= dims[2]) continue;
            for (int dy = -1; dy <= 1; ++dy) {
                const int y = c[1] + dy;
                if (y < 0 || y >= dims[1]) continue;
                for (int dx = -1; dx <= 1; ++dx) {
                    const int x = c[0] + dx;
                    if (x < 0 || x >= dims[0]) continue;
                    const std::int32_t slot = grid[cell_key(x, y, z)];
                    if (slot >= 0) m.add(cells[static_cast<std::size_t>(slot)]);
                }
            }
        }
        if (m.count() < 3.0) continue;
        const Eigen::Vector3d mean = m.sum() / m.count();
        const Eigen::Matrix3d covariance = m.outer() / m.count() - mean * mean.transpose();
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
        solver.computeDirect(covariance);
        const Eigen::Vector3d values = solver.eigenvalues().cwiseMax(0.0);  // ascending
        const double total = values.sum();
        // A point or a line (computeDirect is accurate to about 1e-9 of the largest value).
        if (!(total > 0.0) || values[1] <= 1e-6 * values[2]) continue;
        SurfaceCell s;
        s.position = cells[i].sum() / cells[i].count() + lo;
        s.normal = solver.eigenvectors().col(0).normalized();
        if (s.normal.dot(-s.position) < 0.0) s.normal = -s.normal;
        s.variation = values[0] / total;
        if (!s.position.allFinite() || !s.normal.allFinite()) continue;
        surfels.push_back(s);
    }
    if (surfels.empty())
        throw std::invalid_argument(what + ": no surface normal in a cloud of " +
                                    std::to_string(finite) + " points (too sparse or on a line)");

    return out;
}

}  // namespace esf::detail
