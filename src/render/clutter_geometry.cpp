#include "render/clutter_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "esf/render/view_sphere.hpp"

namespace esf::detail {

double polygon_area(const Hull& hull) {
    double area = 0.0;
    for (std::size_t i = 0; i < hull.size(); ++i) {
        const Vec2& a = hull[i];
        const Vec2& b = hull[(i + 1) % hull.size()];
        area += static_cast<double>(a.x()) * b.y() - static_cast<double>(b.x()) * a.y();
    }
    return 0.5 * std::abs(area);
}

bool polygons_overlap(const Hull& a, const Hull& b) {
    const auto separated_by = [](const Hull& edges, const Hull& other) {
        for (std::size_t i = 0; i < edges.size(); ++i) {
            const Vec2& p = edges[i];
            const Vec2& q = edges[(i + 1) % edges.size()];
            bool all_outside = true;
            for (const Vec2& r : other)
                if (cross(p, q, r) >= 0.0) {
                    all_outside = false;
                    break;
                }
            if (all_outside) return true;
        }
        return false;
    };
    return !separated_by(a, b) && !separated_by(b, a);
}

namespace {

double point_segment_distance(const Vec2& p, const Vec2& a, const Vec2& b) {
    const Eigen::Vector2d ab = (b - a).cast<double>();
    const Eigen::Vector2d ap = (p - a).cast<double>();
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp(ap.dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (ap - t * ab).norm();
}

}  // namespace

double polygon_distance(const Hull& a, const Hull& b) {
    if (polygons_overlap(a, b)) return 0.0;
    double best = std::numeric_limits<double>::infinity();
    for (int pass = 0; pass < 2; ++pass) {
        const Hull& points = pass == 0 ? a : b;
        const Hull& edges = pass == 0 ? b : a;
        for (const Vec2& p : points)
            for (std::size_t i = 0; i < edges.size(); ++i)
                best = std::min(best,
                                point_segment_distance(p, edges[i], edges[(i + 1) % edges.size()]));
    }
    return best;
}

std::vector<Eigen::Vector3d> support_points(const Mesh& mesh) {
    const std::vector<Eigen::Vector3d> directions = view_sphere(2);
    std::vector<std::size_t> best(directions.size(), 0);
    std::vector<double> best_value(directions.size(), -std::numeric_limits<double>::infinity());
    std::vector<Vec2> xy(mesh.vertices.size());
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
        const Eigen::Vector3d p = mesh.vertices[v].cast<double>();
        xy[v] = mesh.vertices[v].head<2>();
        for (std::size_t d = 0; d < directions.size(); ++d) {
            const double value = directions[d].dot(p);
            if (value > best_value[d]) {
                best_value[d] = value;
                best[d] = v;
            }
        }
    }
    std::vector<Eigen::Vector3d> points;
    for (const std::size_t v : best) points.push_back(mesh.vertices[v].cast<double>());
    // The footprint's hull vertices, with the highest z seen at each (any z keeps the hull).
    for (const Vec2& h : convex_hull(xy)) {
        for (const Eigen::Vector3f& v : mesh.vertices)
            if (v.x() == h.x() && v.y() == h.y()) {
                points.push_back(v.cast<double>());
                break;
            }
    }
    std::sort(points.begin(), points.end(), [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
        return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
    });
    points.erase(std::unique(points.begin(), points.end()), points.end());
    return points;
}

ModelShape analyse(const Mesh& mesh) {
    ModelShape shape;
    shape.support = support_points(mesh);
    double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
    for (const Eigen::Vector3d& p : shape.support) {
        zmin = std::min(zmin, p.z());
        zmax = std::max(zmax, p.z());
    }
    shape.height = zmax - zmin;
    std::vector<Vec2> xy, top;
    for (const Eigen::Vector3f& v : mesh.vertices) {
        xy.push_back(v.head<2>());
        if (v.z() >= zmax - 0.05 * shape.height) top.push_back(v.head<2>());
    }
    const Hull footprint = convex_hull(xy);
    if (footprint.size() < 3) return shape;
    const Rectangle rect = min_area_rectangle(footprint);
    const double rect_area = static_cast<double>(rect.length) * rect.width;
    if (!(rect_area > 0.0)) return shape;
    const double fill = polygon_area(footprint) / rect_area;
    const double aspect = rect.length / std::max(rect.width, 1e-9f);
    // A disc fills pi/4 = 0.785 of its square.
    shape.round = footprint.size() >= 8 && fill > 0.7 && fill < 0.88 && aspect < 1.35;
    const Hull top_hull = top.size() >= 3 ? convex_hull(top) : Hull{};
    const double top_area = top_hull.size() >= 3 ? polygon_area(top_hull) : 0.0;
    shape.boxy = fill > 0.9 && top_area > 0.6 * polygon_area(footprint);
    return shape;
}

bool collide(const Body& a, const Body& b, double gap) {
    const double tolerance = 1e-4;
    if (a.zmax <= b.zmin + tolerance || b.zmax <= a.zmin + tolerance) return false;
    if ((a.centre - b.centre).norm() > a.radius + b.radius + gap) return false;
    return gap > 0.0 ? polygon_distance(a.hull, b.hull) < gap : polygons_overlap(a.hull, b.hull);
}

Eigen::Matrix3d rotation_about(const Eigen::Vector3d& axis, double angle) {
    return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

}  // namespace esf::detail
