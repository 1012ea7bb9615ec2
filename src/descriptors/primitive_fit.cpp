#include "esf/descriptors/primitive_fit.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/splitmix64.hpp"
#include "descriptors/cell_features.hpp"

namespace esf {
namespace {

using detail::SurfaceCell;

constexpr double kNormalAgreement = 0.9;  // cos 25.8 degrees
constexpr double kOrthogonal = 0.2;       // |cos| of faces taken as orthogonal (about 78 degrees)
constexpr double kMinAxisSine = 0.3;      // two normals this far apart give an axis
constexpr std::size_t kMinCells = 10;

struct Cylinder {
    Eigen::Vector3d axis;    // unit
    Eigen::Vector3d centre;  // a point on the axis
    double radius = 0.0;
};

/// Whether a cell lies on the cylinder's side (first) or on a lid (second).
std::pair<bool, bool> cylinder_part(const SurfaceCell& c, const Cylinder& cyl, double tol) {
    Eigen::Vector3d d = c.position - cyl.centre;
    d -= d.dot(cyl.axis) * cyl.axis;
    const double distance = d.norm();
    const bool side = std::abs(distance - cyl.radius) < tol && distance > 0.0 &&
                      d.dot(c.normal) > kNormalAgreement * distance;
    const bool lid =
        std::abs(c.normal.dot(cyl.axis)) > kNormalAgreement && distance < cyl.radius + tol;
    return {side, lid};
}

/// A unit vector across `a`.
Eigen::Vector3d across(const Eigen::Vector3d& a) {
    Eigen::Vector3d u = a.cross(Eigen::Vector3d::UnitX());
    if (u.norm() < 0.1) u = a.cross(Eigen::Vector3d::UnitY());
    return u.normalized();
}

/// Circle through 2-D points: algebraic fit (Kasa), then ten Gauss-Newton steps of the geometric
/// distance. Returns false when the points do not fix a circle.
bool fit_circle(const std::vector<Eigen::Vector2d>& p, Eigen::Vector2d& centre, double& radius) {
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    for (const Eigen::Vector2d& q : p) {
        const Eigen::Vector3d row(2.0 * q.x(), 2.0 * q.y(), 1.0);
        ata += row * row.transpose();
        atb += row * q.squaredNorm();
    }
    Eigen::LDLT<Eigen::Matrix3d> ldlt(ata);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
    const Eigen::Vector3d s = ldlt.solve(atb);
    centre = s.head<2>();
    const double r2 = s[2] + centre.squaredNorm();
    if (!(r2 > 0.0) || !s.allFinite()) return false;
    radius = std::sqrt(r2);
    for (int step = 0; step < 10; ++step) {
        Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
        Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
        for (const Eigen::Vector2d& q : p) {
            const Eigen::Vector2d d = q - centre;
            const double n = d.norm() + 1e-12;
            const Eigen::Vector3d j(-d.x() / n, -d.y() / n, -1.0);
            jtj += j * j.transpose();
            jtr += j * (n - radius);
        }
        Eigen::LDLT<Eigen::Matrix3d> solver(jtj);
        if (solver.info() != Eigen::Success) break;
        const Eigen::Vector3d delta = solver.solve(-jtr);
        if (!delta.allFinite()) break;
        centre += delta.head<2>();
        radius += delta[2];
    }
    return std::isfinite(radius) && centre.allFinite();
}

/// Three refinements of a cylinder hypothesis: the axis least across the side normals and most
/// along the lid normals, then centre and radius from a circle fit of the side cells across it.
Cylinder refine(std::span<const SurfaceCell> cells, Cylinder cyl, double tol) {
    for (int round = 0; round < 3; ++round) {
        const double t = round == 0 ? 2.0 * tol : tol;
        Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
        std::vector<const SurfaceCell*> side;
        for (const SurfaceCell& c : cells) {
            const auto [on_side, on_lid] = cylinder_part(c, cyl, t);
            if (on_side) {
                scatter += c.normal * c.normal.transpose();
                side.push_back(&c);
            } else if (on_lid) {
                scatter -= c.normal * c.normal.transpose();
            }
        }
        if (side.size() < 6) break;
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
        solver.computeDirect(scatter);
        const Eigen::Vector3d axis = solver.eigenvectors().col(0).normalized();
        if (!axis.allFinite()) break;
        const Eigen::Vector3d u = across(axis);
        const Eigen::Vector3d v = axis.cross(u);
        std::vector<Eigen::Vector2d> flat;
        flat.reserve(side.size());
        for (const SurfaceCell* c : side) flat.emplace_back(c->position.dot(u), c->position.dot(v));
        Eigen::Vector2d centre;
        double radius = 0.0;
        if (!fit_circle(flat, centre, radius) || !(radius > 0.005 && radius < 1.0)) break;
        cyl = {axis, centre.x() * u + centre.y() * v, radius};
    }
    return cyl;
}

double best_cylinder_share(std::span<const SurfaceCell> cells, std::span<const std::size_t> scored,
                           double extent, double tol, const PrimitiveFitOptions& options,
                           PrimitiveFit& out) {
    detail::SplitMix64 random(detail::mix64(options.seed ^ 0xC7A1D3E5B9F20411ull));
    std::size_t best_count = 0;
    Cylinder best{};
    for (int it = 0; it < options.iterations; ++it) {
        const SurfaceCell& a = cells[random.below(cells.size())];
        const SurfaceCell& b = cells[random.below(cells.size())];
        Eigen::Vector3d axis = a.normal.cross(b.normal);
        const double sine = axis.norm();
        if (sine < kMinAxisSine) continue;
        axis /= sine;
        // The normal lines p - t n of both cells, across the axis, meet at the centre.
        const Eigen::Vector3d pa = a.position - a.position.dot(axis) * axis;
        const Eigen::Vector3d pb = b.position - b.position.dot(axis) * axis;
        const Eigen::Vector3d na = (a.normal - a.normal.dot(axis) * axis).normalized();
        const Eigen::Vector3d nb = (b.normal - b.normal.dot(axis) * axis).normalized();
        Eigen::Matrix<double, 3, 2> m;
        m.col(0) = -na;
        m.col(1) = nb;
        const Eigen::Matrix2d mtm = m.transpose() * m;
        if (!(std::abs(mtm.determinant()) > 1e-12)) continue;
        const Eigen::Vector2d tu = mtm.inverse() * (m.transpose() * (pb - pa));
        const double radius = tu[0];
        if (!(radius > 0.01 && radius < 0.6 * extent + 0.01) || !(tu[1] > 0.0)) continue;
        const Cylinder cyl{axis, pa - radius * na, radius};
        // Counted until the cells left cannot lift it above the best (the same choice, sooner).
        std::size_t count = 0;
        for (std::size_t k = 0; k < scored.size() && count + (scored.size() - k) > best_count;
             ++k) {
            const auto [side, lid] = cylinder_part(cells[scored[k]], cyl, tol);
            count += side || lid;
        }
        if (count > best_count) {
            best_count = count;
            best = cyl;
        }
    }
    if (best_count == 0) return 0.0;
    best = refine(cells, best, tol);
    std::size_t explained = 0;
    for (const SurfaceCell& c : cells) {
        const auto [side, lid] = cylinder_part(c, best, tol);
        explained += side || lid;
    }
    out.radius = best.radius;
    out.axis = best.axis;
    return static_cast<double>(explained) / static_cast<double>(cells.size());
}

double best_box_share(std::span<const SurfaceCell> cells, std::span<const std::size_t> scored,
                      double tol, const PrimitiveFitOptions& options) {
    detail::SplitMix64 random(detail::mix64(options.seed ^ 0x5B0C4E8A1F6D2937ull));
    std::vector<char> free(cells.size(), 1);
    std::vector<Eigen::Vector3d> faces;
    const auto on_face = [&](std::size_t i, const SurfaceCell& seed) {
        const SurfaceCell& c = cells[i];
        return free[i] && std::abs((c.position - seed.position).dot(seed.normal)) < tol &&
               c.normal.dot(seed.normal) > kNormalAgreement;
    };
    std::size_t explained = 0;
    for (int face = 0; face < 3; ++face) {
        std::size_t best_count = 0;
        std::size_t best_seed = 0;
        for (int it = 0; it < options.iterations; ++it) {
            const std::size_t s = random.below(cells.size());
            if (!free[s]) continue;
            const Eigen::Vector3d& n = cells[s].normal;
            if (std::any_of(faces.begin(), faces.end(), [&](const Eigen::Vector3d& f) {
                    return std::abs(f.dot(n)) > kOrthogonal;
                }))
                continue;
            std::size_t count = 0;
            for (std::size_t k = 0; k < scored.size() && count + (scored.size() - k) > best_count;
                 ++k)
                count += on_face(scored[k], cells[s]);
            if (count > best_count) {
                best_count = count;
                best_seed = s;
            }
        }
        if (best_count == 0) break;
        const SurfaceCell seed = cells[best_seed];
        std::size_t taken = 0;
        for (std::size_t i = 0; i < cells.size(); ++i) {
            if (!on_face(i, seed)) continue;
            free[i] = 0;
            ++taken;
        }
        explained += taken;
        faces.push_back(seed.normal);
    }
    return static_cast<double>(explained) / static_cast<double>(cells.size());
}

}  // namespace

namespace detail {

PrimitiveFit fit_primitives(std::span<const SurfaceCell> cells, double cell_size,
                            const PrimitiveFitOptions& options) {
    if (options.iterations < 1)
        throw std::invalid_argument("primitive fit: iterations must be >= 1, got " +
                                    std::to_string(options.iterations));
    if (options.scored_cells < 1)
        throw std::invalid_argument("primitive fit: scored cells must be >= 1");
    PrimitiveFit out;
    out.cells = cells.size();
    if (cells.size() < kMinCells) return out;
    Eigen::Vector3d lo = cells.front().position;
    Eigen::Vector3d hi = lo;
    for (const SurfaceCell& c : cells) {
        lo = lo.cwiseMin(c.position);
        hi = hi.cwiseMax(c.position);
    }
    const double tol = std::max(0.004, 0.6 * cell_size);
    const std::size_t stride =
        std::max<std::size_t>(1, (cells.size() + options.scored_cells - 1) / options.scored_cells);
    std::vector<std::size_t> scored;
    for (std::size_t i = 0; i < cells.size(); i += stride) scored.push_back(i);
    out.cylinder = best_cylinder_share(cells, scored, (hi - lo).norm(), tol, options, out);
    out.box = best_box_share(cells, scored, tol, options);
    return out;
}

}  // namespace detail

PrimitiveFit fit_primitives(std::span<const Eigen::Vector3f> points,
                            const PrimitiveFitOptions& options) {
    const detail::SurfaceCells grid =
        detail::surface_cells(points, options.cell_size, "primitive fit");
    return detail::fit_primitives(grid.cells, grid.cell_size, options);
}

PrimitiveHistogram primitive_histogram(const PrimitiveFit& fit) {
    PrimitiveHistogram h{};
    const double contrast = std::clamp(fit.cylinder - fit.box, -1.0, 1.0);
    // Bin centres at -1 + (k + 0.5) * width.
    constexpr double kWidth = 2.0 / kPrimitiveBins;
    const double t = std::clamp((contrast + 1.0) / kWidth - 0.5, 0.0, kPrimitiveBins - 1.0);
    const int low = std::min(static_cast<int>(std::floor(t)), kPrimitiveBins - 2);
    const double high_share = t - low;
    h[static_cast<std::size_t>(low)] = static_cast<float>(1.0 - high_share);
    h[static_cast<std::size_t>(low + 1)] = static_cast<float>(high_share);
    return h;
}

double primitive_contrast(std::span<const float> histogram) {
    if (histogram.size() != static_cast<std::size_t>(kPrimitiveBins))
        return std::numeric_limits<double>::quiet_NaN();
    constexpr double kWidth = 2.0 / kPrimitiveBins;
    double sum = 0.0, weighted = 0.0;
    for (std::size_t k = 0; k < histogram.size(); ++k) {
        const double share = histogram[k];
        sum += share;
        weighted += share * (-1.0 + (static_cast<double>(k) + 0.5) * kWidth);
    }
    return sum > 0.0 && std::isfinite(sum) ? weighted / sum
                                           : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace esf
