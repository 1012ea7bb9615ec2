#include "occluded_parts.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "disjoint_sets.hpp"

namespace esf::detail {

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

struct GroupPlane {
    std::size_t points = 0;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    double rms = std::numeric_limits<double>::infinity();
    double u = 0.0, v = 0.0;  // image centroid
};

}  // namespace

void join_occluded_parts(std::span<const Eigen::Vector3f> points, std::uint32_t width,
                         std::uint32_t height, std::span<const std::uint32_t> candidates,
                         std::vector<std::uint32_t>& component, const Eigen::Vector3f& viewpoint,
                         const OccludedPartsOptions& options) {
    if (component.empty()) return;
    const std::uint32_t count = *std::max_element(component.begin(), component.end()) + 1;
    // Plane of each group (sums relative to the first point of the group).
    std::vector<GroupPlane> groups(count);
    std::vector<Eigen::Vector3d> origin(count), sum(count, Eigen::Vector3d::Zero());
    std::vector<Eigen::Matrix3d> outer(count, Eigen::Matrix3d::Zero());
    std::vector<std::uint32_t> group_at(static_cast<std::size_t>(width) * height, kNone);
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        const std::uint32_t g = component[k];
        const Eigen::Vector3d p = points[candidates[k]].cast<double>();
        if (groups[g].points == 0) origin[g] = p;
        const Eigen::Vector3d d = p - origin[g];
        sum[g] += d;
        outer[g] += d * d.transpose();
        ++groups[g].points;
        groups[g].u += candidates[k] % width;
        groups[g].v += candidates[k] / width;
        group_at[candidates[k]] = g;
    }
    std::vector<std::uint32_t> planar;
    for (std::uint32_t g = 0; g < count; ++g) {
        GroupPlane& plane = groups[g];
        const double n = static_cast<double>(plane.points);
        plane.u /= n;
        plane.v /= n;
        if (plane.points < options.min_points) continue;
        const Eigen::Vector3d mean = sum[g] / n;
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
        solver.computeDirect(outer[g] / n - mean * mean.transpose());
        plane.centroid = origin[g] + mean;
        plane.normal = solver.eigenvectors().col(0).normalized();
        plane.rms = std::sqrt(std::max(0.0, solver.eigenvalues()[0]));
        if (plane.normal.dot(viewpoint.cast<double>() - plane.centroid) < 0.0)
            plane.normal = -plane.normal;
        if (plane.rms <= options.max_plane_rms && plane.normal.allFinite()) planar.push_back(g);
    }

    const double cos_max = std::cos(static_cast<double>(options.max_normal_angle_deg) * M_PI / 180);
    const Eigen::Vector3d eye = viewpoint.cast<double>();
    // Whether the image line between the two groups' centroids passes only through them or
    // in front of their common plane.
    auto bridged = [&](std::uint32_t a, std::uint32_t b, const Eigen::Vector3d& normal,
                       const Eigen::Vector3d& on_plane) {
        const GroupPlane &ga = groups[a], &gb = groups[b];
        const double du = gb.u - ga.u, dv = gb.v - ga.v;
        const int steps = static_cast<int>(std::ceil(std::max(std::abs(du), std::abs(dv))));
        if (steps < 1) return true;
        int invalid = 0, occluded = 0;
        for (int s = 0; s <= steps; ++s) {
            const auto u = static_cast<std::uint32_t>(std::lround(ga.u + du * s / steps));
            const auto v = static_cast<std::uint32_t>(std::lround(ga.v + dv * s / steps));
            if (u >= width || v >= height) return false;
            const std::size_t pixel = static_cast<std::size_t>(v) * width + u;
            const std::uint32_t g = group_at[pixel];
            if (g == a || g == b) continue;
            const Eigen::Vector3d p = points[pixel].cast<double>();
            if (!p.allFinite()) {
                ++invalid;
                continue;
            }
            // Where the pixel's ray meets the common plane, and how far in front the point is.
            const Eigen::Vector3d ray = p - eye;
            const double along = normal.dot(ray);
            if (std::abs(along) < 1e-12) return false;
            const double t = normal.dot(on_plane - eye) / along;  // plane at eye + t * ray
            if (!(t > 1.0)) return false;                          // the point is not in front
            if ((t - 1.0) * ray.norm() < options.min_occluder_gap) return false;
            ++occluded;
        }
        return occluded > 0 && invalid <= options.max_invalid_share * (steps + 1);
    };
    DisjointSets sets(count);
    for (std::size_t i = 0; i < planar.size(); ++i)
        for (std::size_t j = i + 1; j < planar.size(); ++j) {
            const std::uint32_t a = planar[i], b = planar[j];
            const GroupPlane &ga = groups[a], &gb = groups[b];
            if (ga.normal.dot(gb.normal) < cos_max) continue;
            if (std::abs(ga.normal.dot(gb.centroid - ga.centroid)) > options.max_plane_offset ||
                std::abs(gb.normal.dot(ga.centroid - gb.centroid)) > options.max_plane_offset)
                continue;
            const double wa = static_cast<double>(ga.points), wb = static_cast<double>(gb.points);
            const Eigen::Vector3d normal = (wa * ga.normal + wb * gb.normal).normalized();
            const Eigen::Vector3d on_plane = (wa * ga.centroid + wb * gb.centroid) / (wa + wb);
            if (bridged(a, b, normal, on_plane)) sets.unite(a, b);
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
