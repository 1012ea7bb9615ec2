#include "core/convex_hull_2d.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

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

ConvexRegion::ConvexRegion(std::vector<Vec2> polygon) : polygon_(std::move(polygon)) {
    Vec2 lo = polygon_.front(), hi = polygon_.front();
    for (const Vec2& p : polygon_) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    lo_ = lo;
    hi_ = hi;
    const float width = hi.x() - lo.x(), height = hi.y() - lo.y();
    if (!(width > 0.0f && height > 0.0f && std::isfinite(width) && std::isfinite(height)))
        return;  // no grid: every test takes inside_convex()
    x0_ = lo.x();
    y0_ = lo.y();
    scale_x_ = static_cast<float>(kCells) / width;
    scale_y_ = static_cast<float>(kCells) / height;
    constexpr int corners = kCells + 1;
    std::vector<std::uint8_t> corner_in(corners * corners);
    for (int j = 0; j < corners; ++j)
        for (int i = 0; i < corners; ++i) {
            const Vec2 c(lo.x() + width * static_cast<float>(i) / kCells,
                         lo.y() + height * static_cast<float>(j) / kCells);
            corner_in[static_cast<std::size_t>(j * corners + i)] = inside_convex(polygon_, c);
        }
    std::vector<std::uint8_t> cell_in(kCells * kCells);
    for (int j = 0; j < kCells; ++j)
        for (int i = 0; i < kCells; ++i) {
            const auto at = [&](int a, int b) {
                return corner_in[static_cast<std::size_t>(b * corners + a)];
            };
            cell_in[static_cast<std::size_t>(j * kCells + i)] =
                at(i, j) && at(i + 1, j) && at(i, j + 1) && at(i + 1, j + 1);
        }
    deep_.assign(kCells * kCells, 0);
    for (int j = 1; j + 1 < kCells; ++j)
        for (int i = 1; i + 1 < kCells; ++i) {
            bool all = true;
            for (int b = j - 1; b <= j + 1 && all; ++b)
                for (int a = i - 1; a <= i + 1 && all; ++a)
                    all = cell_in[static_cast<std::size_t>(b * kCells + a)] != 0;
            deep_[static_cast<std::size_t>(j * kCells + i)] = all;
        }
}

bool ConvexRegion::contains(const Vec2& q) const {
    if (!deep_.empty()) {
        const float fx = (q.x() - x0_) * scale_x_, fy = (q.y() - y0_) * scale_y_;
        if (fx >= 0.0f && fy >= 0.0f && fx < static_cast<float>(kCells) &&
            fy < static_cast<float>(kCells) &&
            deep_[static_cast<std::size_t>(static_cast<int>(fy) * kCells + static_cast<int>(fx))])
            return true;
    }
    return inside_convex(polygon_, q);
}

bool ConvexRegion::contains(const Vec2& q, float margin) const {
    if (contains(q)) return true;
    if (!(margin > 0.0f)) return false;
    if ((q - lo_).minCoeff() < -margin || (hi_ - q).minCoeff() < -margin) return false;
    const float reach = margin * margin;
    for (std::size_t e = 0; e < polygon_.size(); ++e) {
        const Vec2& a = polygon_[e];
        const Vec2 ab = polygon_[(e + 1) % polygon_.size()] - a;
        const float length = ab.squaredNorm();
        const float t = length > 0.0f ? std::clamp((q - a).dot(ab) / length, 0.0f, 1.0f) : 0.0f;
        if ((a + t * ab - q).squaredNorm() <= reach) return true;
    }
    return false;
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
