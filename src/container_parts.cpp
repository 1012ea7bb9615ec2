#include "container_parts.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "disjoint_sets.hpp"

namespace esf::detail {

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

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

}  // namespace

void join_container_parts(std::span<const Eigen::Vector3f> points,
                          std::vector<std::uint32_t>& component, const Eigen::Vector3f& up,
                          float offset, const ContainerPartsOptions& options) {
    if (component.empty()) return;
    const std::uint32_t count = *std::max_element(component.begin(), component.end()) + 1;
    const Eigen::Vector3f helper =
        std::abs(up.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
    const Eigen::Vector3f u = up.cross(helper).normalized(), w = up.cross(u);
    std::vector<std::vector<Eigen::Vector2d>> footprint(count);
    std::vector<float> top(count, -std::numeric_limits<float>::infinity());
    for (std::size_t k = 0; k < points.size(); ++k) {
        footprint[component[k]].emplace_back(u.dot(points[k]), w.dot(points[k]));
        top[component[k]] = std::max(top[component[k]], up.dot(points[k]) + offset);
    }
    std::vector<std::uint32_t> large;
    std::vector<Circle> circles(count);
    for (std::uint32_t g = 0; g < count; ++g) {
        if (footprint[g].size() < options.min_points) continue;
        large.push_back(g);
        circles[g] = fit_circle(footprint[g]);
    }
    DisjointSets sets(count);
    for (const std::uint32_t outer : large) {
        const Circle& c = circles[outer];
        if (!(c.radius >= options.min_radius && c.radius <= options.max_radius &&
              c.rms <= options.max_residual * c.radius))
            continue;
        const double reach = c.radius + options.margin;
        for (const std::uint32_t inner : large) {
            if (inner == outer || top[inner] > top[outer] + options.margin) continue;
            std::size_t inside = 0;
            for (const Eigen::Vector2d& q : footprint[inner])
                inside += (q - c.centre).squaredNorm() <= reach * reach;
            if (static_cast<double>(inside) >=
                static_cast<double>(options.min_inside) *
                    static_cast<double>(footprint[inner].size()))
                sets.unite(outer, inner);
        }
    }
    std::vector<std::uint32_t> number(count, kNone);
    std::uint32_t next = 0;
    for (std::uint32_t& c : component) {
        const std::uint32_t root = sets.find(c);
        if (number[root] == kNone) number[root] = next++;
        c = number[root];
    }
}

}  // namespace esf::detail
