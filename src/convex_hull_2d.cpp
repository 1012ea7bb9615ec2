#include "convex_hull_2d.hpp"

#include <algorithm>
#include <cmath>

namespace esf::detail {

double cross(const Vec2& o, const Vec2& a, const Vec2& b) {
    return (static_cast<double>(a.x()) - o.x()) * (static_cast<double>(b.y()) - o.y()) -
           (static_cast<double>(a.y()) - o.y()) * (static_cast<double>(b.x()) - o.x());
}

/// Andrew's monotone chain: the convex hull counter-clockwise, without collinear vertices.
std::vector<Vec2> monotone_chain(std::vector<Vec2> points) {
    std::sort(points.begin(), points.end(), [](const Vec2& a, const Vec2& b) {
        return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
    points.erase(std::unique(points.begin(), points.end()), points.end());
    if (points.size() < 3) return points;
    std::vector<Vec2> hull(2 * points.size());
    std::size_t k = 0;
    for (const Vec2& p : points) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], p) <= 0.0) --k;
        hull[k++] = p;
    }
    for (std::size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
        hull[k++] = points[i];
    }
    hull.resize(k - 1);
    return hull;
}

std::vector<Vec2> convex_hull(std::span<const Vec2> points) {
    Octagon octagon;
    for (const Vec2& p : points) octagon.add(p);
    std::vector<Vec2> candidates;
    octagon.append_outside(points, candidates);
    return monotone_chain(std::move(candidates));
}

/// Point in a convex counter-clockwise polygon (boundary counts as inside), O(log n).
bool inside_convex(std::span<const Vec2> hull, const Vec2& q) {
    const std::size_t n = hull.size();
    if (cross(hull[0], hull[1], q) < 0.0 || cross(hull[0], hull[n - 1], q) > 0.0) return false;
    std::size_t lo = 1, hi = n - 1;  // find the wedge hull[0], hull[lo], hull[lo + 1]
    while (hi - lo > 1) {
        const std::size_t mid = (lo + hi) / 2;
        if (cross(hull[0], hull[mid], q) >= 0.0)
            lo = mid;
        else
            hi = mid;
    }
    return cross(hull[lo], hull[lo + 1], q) >= 0.0;
}

/// Smallest-area rectangle holding a strictly convex counter-clockwise polygon: one side lies
/// on a hull edge (Freeman & Shapira 1975); rotating calipers (Toussaint 1983) find the extreme
/// vertices of every edge in O(n) overall.
Rectangle min_area_rectangle(std::span<const Vec2> hull) {
    Rectangle best;
    const std::size_t n = hull.size();
    if (n == 2) {
        const Vec2 e = hull[1] - hull[0];
        best.length = e.norm();
        if (best.length > 0.0f) best.length_axis = e / best.length;
        return best;
    }
    if (n < 3) return best;
    auto at = [&](std::size_t i) -> Eigen::Vector2d { return hull[i % n].cast<double>(); };
    auto step = [&](std::size_t i) -> Eigen::Vector2d { return at(i + 1) - at(i); };
    double best_area = std::numeric_limits<double>::infinity();
    std::size_t far = 0, top = 0, near = 0;  // extreme along the edge, from it, against it
    bool first = true;
    for (std::size_t i = 0; i < n; ++i) {
        Eigen::Vector2d e = step(i);
        const double e_norm = e.norm();
        if (e_norm == 0.0) continue;
        e /= e_norm;
        const Eigen::Vector2d inward(-e.y(), e.x());
        if (first) far = i + 1;
        for (std::size_t guard = 0; guard < n && step(far).dot(e) > 0.0; ++guard) ++far;
        if (first) top = far;
        for (std::size_t guard = 0; guard < n && step(top).dot(inward) > 0.0; ++guard) ++top;
        if (first) near = top;
        for (std::size_t guard = 0; guard < n && step(near).dot(e) < 0.0; ++guard) ++near;
        first = false;
        const double la = (at(far) - at(near)).dot(e);
        const double lb = (at(top) - at(i)).dot(inward);
        if (la * lb < best_area) {
            best_area = la * lb;
            best.length = static_cast<float>(std::max(la, lb));
            best.width = static_cast<float>(std::min(la, lb));
            best.length_axis = (la >= lb ? e : inward).cast<float>();
        }
    }
    return best;
}

}  // namespace esf::detail
