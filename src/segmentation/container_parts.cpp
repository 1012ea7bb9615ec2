#include "segmentation/container_parts.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>

#include "core/disjoint_sets.hpp"
#include "segmentation/plane_fit.hpp"

namespace esf::detail {

namespace {

struct Circle {
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    double radius = 0.0;
    double rms = std::numeric_limits<double>::infinity();
};

/// Sums of a 2-D point set about a fixed origin, enough for a least-squares circle: n, x, y,
/// xx, xy, yy, xz, yz, z with z = x^2 + y^2. Two sets' sums add.
struct CircleSums {
    std::array<double, 9> s{};

    void add(const Eigen::Vector2d& q) {
        const double z = q.squaredNorm();
        s[0] += 1.0;
        s[1] += q.x();
        s[2] += q.y();
        s[3] += q.x() * q.x();
        s[4] += q.x() * q.y();
        s[5] += q.y() * q.y();
        s[6] += q.x() * z;
        s[7] += q.y() * z;
        s[8] += z;
    }
    CircleSums operator+(const CircleSums& o) const {
        CircleSums out;
        for (std::size_t i = 0; i < s.size(); ++i) out.s[i] = s[i] + o.s[i];
        return out;
    }
};

/// Least-squares circle (Kasa 1976: x^2 + y^2 + D x + E y + F = 0) from the sums of points;
/// the residual is not computed here (rms stays infinite).
Circle fit_circle(const CircleSums& sums) {
    Circle c;
    const auto& s = sums.s;
    if (s[0] < 3.0) return c;
    Eigen::Matrix3d ata;
    ata << s[3], s[4], s[1], s[4], s[5], s[2], s[1], s[2], s[0];
    const Eigen::Vector3d atb(-s[6], -s[7], -s[8]);
    const Eigen::Vector3d x = ata.ldlt().solve(atb);
    if (!x.allFinite()) return c;
    c.centre = Eigen::Vector2d(-x[0] / 2, -x[1] / 2);
    const double r2 = c.centre.squaredNorm() - x[2];
    if (!(r2 > 0.0)) return c;
    c.radius = std::sqrt(r2);
    return c;
}

/// Sum of squared radial residuals of points to `c`.
double radial_sum(const Circle& c, std::span<const Eigen::Vector2d> p) {
    double sum = 0.0;
    for (const Eigen::Vector2d& q : p) {
        const double e = (q - c.centre).norm() - c.radius;
        sum += e * e;
    }
    return sum;
}

/// An axis-aligned box of 2-D points (empty until the first point).
struct Box {
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0;
    double x1 = -std::numeric_limits<double>::infinity(), y1 = x1;

    void extend(const Eigen::Vector2d& q) {
        x0 = std::min(x0, q.x());
        y0 = std::min(y0, q.y());
        x1 = std::max(x1, q.x());
        y1 = std::max(y1, q.y());
    }
};

/// Gap between two boxes (0 when they overlap).
double box_gap(const Box& a, const Box& b) {
    const double gx = std::max({b.x0 - a.x1, a.x0 - b.x1, 0.0});
    const double gy = std::max({b.y0 - a.y1, a.y0 - b.y1, 0.0});
    return std::sqrt(gx * gx + gy * gy);
}

}  // namespace

void join_container_parts(std::span<const Eigen::Vector3f> points,
                          std::vector<std::uint32_t>& component, const Eigen::Vector3f& up,
                          float offset, const ContainerPartsOptions& options) {
    if (component.empty()) return;
    const std::uint32_t count = *std::max_element(component.begin(), component.end()) + 1;
    const auto [u, w] = plane_basis(up);
    // Table-plane coordinates about the first point, so that the circle sums stay small.
    const Eigen::Vector2d origin(u.dot(points[0]), w.dot(points[0]));
    const auto planar = [&](const Eigen::Vector3f& p) -> Eigen::Vector2d {
        return Eigen::Vector2d(u.dot(p), w.dot(p)) - origin;
    };
    // Each group's points contiguous (a counting sort by group): footprint(g) and rim(g) are
    // ranges of two shared buffers, filled without an allocation per group.
    std::vector<std::size_t> first(count + 1, 0);
    for (const std::uint32_t g : component) ++first[g + 1];
    for (std::uint32_t g = 0; g < count; ++g) first[g + 1] += first[g];
    std::vector<Eigen::Vector2d> footprint_points(points.size());
    std::vector<float> heights(points.size());
    std::vector<CircleSums> footprint_sums(count), rim_sums(count);
    std::vector<Box> footprint_box(count), rim_box(count);
    std::vector<float> top(count, -std::numeric_limits<float>::infinity());
    {
        std::vector<std::size_t> next(first.begin(), first.end() - 1);
        for (std::size_t k = 0; k < points.size(); ++k) {
            const std::uint32_t g = component[k];
            const std::size_t slot = next[g]++;
            const Eigen::Vector2d q = planar(points[k]);
            footprint_points[slot] = q;
            heights[slot] = up.dot(points[k]) + offset;
            footprint_sums[g].add(q);
            footprint_box[g].extend(q);
            top[g] = std::max(top[g], heights[slot]);
        }
    }
    // The upper part of each group, where a container's walls are steep and its outline round.
    std::vector<Eigen::Vector2d> rim_points;
    rim_points.reserve(points.size());
    std::vector<std::size_t> rim_first(count + 1, 0);
    for (std::uint32_t g = 0; g < count; ++g) {
        for (std::size_t i = first[g]; i < first[g + 1]; ++i)
            if (heights[i] >= options.rim_band * top[g]) {
                rim_points.push_back(footprint_points[i]);
                rim_sums[g].add(footprint_points[i]);
                rim_box[g].extend(footprint_points[i]);
            }
        rim_first[g + 1] = rim_points.size();
    }
    const auto footprint = [&](std::uint32_t g) {
        return std::span<const Eigen::Vector2d>(footprint_points.data() + first[g],
                                                first[g + 1] - first[g]);
    };
    const auto rim = [&](std::uint32_t g) {
        return std::span<const Eigen::Vector2d>(rim_points.data() + rim_first[g],
                                                rim_first[g + 1] - rim_first[g]);
    };
    auto round = [&](const Circle& c) {
        return c.radius >= options.min_radius && c.radius <= options.max_radius &&
               c.rms <= options.max_residual * c.radius;
    };
    auto plausible = [&](const Circle& c) {  // the radius test alone, before any residual
        return c.radius >= options.min_radius && c.radius <= options.max_radius;
    };
    std::vector<std::uint32_t> large;
    std::vector<Circle> circles(count);
    for (std::uint32_t g = 0; g < count; ++g) {
        if (footprint(g).size() < options.min_points) continue;
        large.push_back(g);
        Circle& c = circles[g];
        c = fit_circle(footprint_sums[g]);
        if (plausible(c))
            c.rms =
                std::sqrt(radial_sum(c, footprint(g)) / static_cast<double>(footprint(g).size()));
    }
    DisjointSets sets(count);
    // Two parts of one round wall: the upper parts of both lie on one circle.
    for (std::size_t i = 0; i < large.size(); ++i)
        for (std::size_t j = i + 1; j < large.size(); ++j) {
            const std::uint32_t a = large[i], b = large[j];
            if (rim(a).size() < options.min_points / 4 || rim(b).size() < options.min_points / 4)
                continue;
            if (box_gap(rim_box[a], rim_box[b]) > options.max_shared_gap) continue;
            Circle c = fit_circle(rim_sums[a] + rim_sums[b]);
            if (!plausible(c) || c.radius > options.max_shared_radius) continue;
            const double sum_a = radial_sum(c, rim(a)), sum_b = radial_sum(c, rim(b));
            c.rms = std::sqrt((sum_a + sum_b) / static_cast<double>(rim(a).size() + rim(b).size()));
            const double limit = options.max_shared_residual * c.radius;
            if (!round(c) || c.rms > limit) continue;
            if (std::sqrt(sum_a / static_cast<double>(rim(a).size())) <= limit &&
                std::sqrt(sum_b / static_cast<double>(rim(b).size())) <= limit)
                sets.unite(a, b);
        }
    for (const std::uint32_t outer : large) {
        const Circle& c = circles[outer];
        if (!round(c)) continue;
        const double reach = c.radius + options.margin;
        Box disc;  // the square around the reach: a footprint outside it has no point inside
        disc.x0 = c.centre.x() - reach;
        disc.y0 = c.centre.y() - reach;
        disc.x1 = c.centre.x() + reach;
        disc.y1 = c.centre.y() + reach;
        for (const std::uint32_t inner : large) {
            if (inner == outer || top[inner] > top[outer] + options.margin) continue;
            if (box_gap(disc, footprint_box[inner]) > 0.0) continue;
            std::size_t inside = 0;
            for (const Eigen::Vector2d& q : footprint(inner))
                inside += (q - c.centre).squaredNorm() <= reach * reach;
            if (static_cast<double>(inside) >= static_cast<double>(options.min_inside) *
                                                   static_cast<double>(footprint(inner).size()))
                sets.unite(outer, inner);
        }
    }
    sets.number_sets(component);
}

std::size_t join_container_floors(std::span<const Eigen::Vector3f> points, std::uint32_t width,
                                  const Plane& plane, float min_height,
                                  std::vector<Cluster>& clusters,
                                  const ContainerPartsOptions& options) {
    if (clusters.empty() || width == 0) return 0;
    const Eigen::Vector3f& up = plane.normal;
    const auto [u, w] = plane_basis(up);
    const auto planar = [&](const Eigen::Vector3f& p) {
        return Eigen::Vector2d(u.dot(p), w.dot(p));
    };
    std::vector<bool> held(points.size(), false);
    for (const Cluster& c : clusters)
        for (const std::uint32_t i : c.indices) held[i] = true;
    std::size_t taken = 0;
    for (Cluster& cluster : clusters) {
        if (cluster.indices.size() < options.min_points) continue;
        float top = -std::numeric_limits<float>::infinity();
        for (const Eigen::Vector3f& p : cluster.points) top = std::max(top, plane.height(p));
        if (!(top > min_height)) continue;
        // The upper part's circle, about its first point (small sums).
        std::vector<Eigen::Vector2d> rim;
        Eigen::Vector2d origin = Eigen::Vector2d::Zero();
        CircleSums sums;
        for (const Eigen::Vector3f& p : cluster.points)
            if (plane.height(p) >= options.rim_band * top) {
                if (rim.empty()) origin = planar(p);
                rim.push_back(planar(p) - origin);
                sums.add(rim.back());
            }
        if (rim.size() < options.min_points / 4) continue;
        Circle c = fit_circle(sums);
        if (!(c.radius >= options.min_radius && c.radius <= options.max_radius)) continue;
        c.rms = std::sqrt(radial_sum(c, rim) / static_cast<double>(rim.size()));
        if (c.rms > options.max_residual * c.radius) continue;
        const double reach = c.radius - options.margin;
        if (!(reach > 0.0)) continue;
        // The cluster's pixel bounding box.
        std::uint32_t row0 = std::numeric_limits<std::uint32_t>::max(), row1 = 0;
        std::uint32_t col0 = row0, col1 = 0;
        for (const std::uint32_t i : cluster.indices) {
            row0 = std::min(row0, i / width);
            row1 = std::max(row1, i / width);
            col0 = std::min(col0, i % width);
            col1 = std::max(col1, i % width);
        }
        // The floor is seen through the opening, walled in on all four sides in the image; the
        // table under an overhanging rim is not (nothing of the object below it).
        constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
        std::vector<std::uint32_t> row_first(row1 - row0 + 1, kNone), row_last(row1 - row0 + 1, 0);
        std::vector<std::uint32_t> col_first(col1 - col0 + 1, kNone), col_last(col1 - col0 + 1, 0);
        for (const std::uint32_t i : cluster.indices) {
            const std::uint32_t row = i / width, col = i % width;
            row_first[row - row0] = std::min(row_first[row - row0], col);
            row_last[row - row0] = std::max(row_last[row - row0], col);
            col_first[col - col0] = std::min(col_first[col - col0], row);
            col_last[col - col0] = std::max(col_last[col - col0], row);
        }
        std::vector<std::uint32_t> floor;
        for (std::uint32_t row = row0; row <= row1; ++row)
            for (std::uint32_t col = col0; col <= col1; ++col) {
                const std::uint32_t i = row * width + col;
                const Eigen::Vector3f& p = points[i];
                if (held[i] || !p.allFinite() || !(std::abs(plane.height(p)) < min_height))
                    continue;
                if (row_first[row - row0] == kNone || !(row_first[row - row0] < col) ||
                    !(col < row_last[row - row0]) || col_first[col - col0] == kNone ||
                    !(col_first[col - col0] < row) || !(row < col_last[col - col0]))
                    continue;
                if ((planar(p) - origin - c.centre).squaredNorm() < reach * reach)
                    floor.push_back(i);
            }
        if (floor.empty()) continue;
        for (const std::uint32_t i : floor) held[i] = true;
        taken += floor.size();
        std::vector<std::uint32_t> indices(cluster.indices.size() + floor.size());
        std::merge(cluster.indices.begin(), cluster.indices.end(), floor.begin(), floor.end(),
                   indices.begin());
        cluster.indices = std::move(indices);
        cluster.points.clear();
        cluster.points.reserve(cluster.indices.size());
        for (const std::uint32_t i : cluster.indices) cluster.points.push_back(points[i]);
    }
    return taken;
}

}  // namespace esf::detail
