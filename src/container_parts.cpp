#include "container_parts.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "disjoint_sets.hpp"

namespace esf::detail {

namespace {

struct Circle {
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    double radius = 0.0;
    double rms = std::numeric_limits<double>::infinity();
};

/// Least-squares circle through 2-D points (Kasa 1976): x^2 + y^2 + D x + E y + F = 0.
Circle fit_circle(const std::vector<Eigen::Vector2d>& p) {
    Circle c;
    if (p.size() < 3) return c;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& q : p) mean += q;
    mean /= static_cast<double>(p.size());
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    for (const Eigen::Vector2d& q : p) {
        const Eigen::Vector2d d = q - mean;
        const Eigen::Vector3d row(d.x(), d.y(), 1.0);
        ata += row * row.transpose();
        atb -= row * d.squaredNorm();
    }
    const Eigen::Vector3d x = ata.ldlt().solve(atb);
    if (!x.allFinite()) return c;
    const Eigen::Vector2d centre(-x[0] / 2, -x[1] / 2);
    const double r2 = centre.squaredNorm() - x[2];
    if (!(r2 > 0.0)) return c;
    c.centre = centre + mean;
    c.radius = std::sqrt(r2);
    double sum = 0.0;
    for (const Eigen::Vector2d& q : p) {
        const double e = (q - c.centre).norm() - c.radius;
        sum += e * e;
    }
    c.rms = std::sqrt(sum / static_cast<double>(p.size()));
    return c;
}

/// Gap between the bounding boxes of two point sets (0 when they overlap).
double box_gap(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
    Eigen::Vector2d lo_a = a.front(), hi_a = a.front(), lo_b = b.front(), hi_b = b.front();
    for (const Eigen::Vector2d& q : a) {
        lo_a = lo_a.cwiseMin(q);
        hi_a = hi_a.cwiseMax(q);
    }
    for (const Eigen::Vector2d& q : b) {
        lo_b = lo_b.cwiseMin(q);
        hi_b = hi_b.cwiseMax(q);
    }
    return (lo_b - hi_a).cwiseMax(lo_a - hi_b).cwiseMax(0.0).norm();
}

double rms_to(const Circle& c, const std::vector<Eigen::Vector2d>& p) {
    double sum = 0.0;
    for (const Eigen::Vector2d& q : p) {
        const double e = (q - c.centre).norm() - c.radius;
        sum += e * e;
    }
    return p.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(p.size()));
}

}  // namespace

void join_container_parts(std::span<const Eigen::Vector3f> points,
                          std::vector<std::uint32_t>& component, const Eigen::Vector3f& up,
                          float offset, const ContainerPartsOptions& options) {
    if (component.empty()) return;
    const std::uint32_t count = *std::max_element(component.begin(), component.end()) + 1;
    const Eigen::Vector3f helper =
        std::abs(up.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
    const Eigen::Vector3f u = up.cross(helper).normalized(), w = up.cross(u);
    std::vector<std::vector<Eigen::Vector2d>> footprint(count), rim(count);
    std::vector<float> top(count, -std::numeric_limits<float>::infinity());
    for (std::size_t k = 0; k < points.size(); ++k) {
        footprint[component[k]].emplace_back(u.dot(points[k]), w.dot(points[k]));
        top[component[k]] = std::max(top[component[k]], up.dot(points[k]) + offset);
    }
    // The upper part of each group, where a container's walls are steep and its outline round.
    for (std::size_t k = 0; k < points.size(); ++k)
        if (up.dot(points[k]) + offset >= options.rim_band * top[component[k]])
            rim[component[k]].emplace_back(u.dot(points[k]), w.dot(points[k]));
    std::vector<std::uint32_t> large;
    std::vector<Circle> circles(count);
    for (std::uint32_t g = 0; g < count; ++g) {
        if (footprint[g].size() < options.min_points) continue;
        large.push_back(g);
        circles[g] = fit_circle(footprint[g]);
    }
    DisjointSets sets(count);
    auto round = [&](const Circle& c) {
        return c.radius >= options.min_radius && c.radius <= options.max_radius &&
               c.rms <= options.max_residual * c.radius;
    };
    // Two parts of one round wall: the upper parts of both lie on one circle.
    std::vector<Eigen::Vector2d> both;
    for (std::size_t i = 0; i < large.size(); ++i)
        for (std::size_t j = i + 1; j < large.size(); ++j) {
            const std::uint32_t a = large[i], b = large[j];
            if (rim[a].size() < options.min_points / 4 || rim[b].size() < options.min_points / 4)
                continue;
            if (box_gap(rim[a], rim[b]) > options.max_shared_gap) continue;
            both = rim[a];
            both.insert(both.end(), rim[b].begin(), rim[b].end());
            const Circle c = fit_circle(both);
            if (!round(c) || c.radius > options.max_shared_radius) continue;
            const double limit = options.max_shared_residual * c.radius;
            if (c.rms <= limit && rms_to(c, rim[a]) <= limit && rms_to(c, rim[b]) <= limit)
                sets.unite(a, b);
        }
    for (const std::uint32_t outer : large) {
        const Circle& c = circles[outer];
        if (!round(c)) continue;
        const double reach = c.radius + options.margin;
        for (const std::uint32_t inner : large) {
            if (inner == outer || top[inner] > top[outer] + options.margin) continue;
            std::size_t inside = 0;
            for (const Eigen::Vector2d& q : footprint[inner])
                inside += (q - c.centre).squaredNorm() <= reach * reach;
            if (static_cast<double>(inside) >= static_cast<double>(options.min_inside) *
                                                   static_cast<double>(footprint[inner].size()))
                sets.unite(outer, inner);
        }
    }
    sets.number_sets(component);
}

}  // namespace esf::detail
