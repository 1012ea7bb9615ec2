#pragma once
// Convex hulls in the plane (segmentation.hpp, step 3, and the object boxes): the octagon
// filter, Andrew's monotone chain, point-in-hull tests and the smallest-area rectangle.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace esf::detail {

using Vec2 = Eigen::Vector2f;

/// Twice the signed area of the triangle (o, a, b): positive when a -> b turns left seen from o.
double cross(const Vec2& o, const Vec2& a, const Vec2& b);

/// The extreme points of a point set in eight directions. No point strictly inside their
/// polygon can be a vertex of the convex hull (Akl & Toussaint 1978), which leaves few points
/// to sort. Octagons of parts of a set merge into the octagon of the whole.
class Octagon {
  public:
    void add(const Vec2& p) {
        for (int k = 0; k < 8; ++k) {
            const float v = kDirections[k][0] * p.x() + kDirections[k][1] * p.y();
            if (v > best_[k]) {
                best_[k] = v;
                point_[k] = p;
            }
        }
    }

    void merge(const Octagon& other) {
        for (int k = 0; k < 8; ++k)
            if (other.best_[k] > best_[k]) {
                best_[k] = other.best_[k];
                point_[k] = other.point_[k];
            }
    }

    /// Appends the points of `points` that are not strictly inside the octagon to `out`.
    void append_outside(std::span<const Vec2> points, std::vector<Vec2>& out) const {
        // Edges as lines a x + b y + c = 0, positive inside (the polygon is counter-clockwise).
        std::array<std::array<double, 3>, 8> lines{};
        std::size_t count = 0;
        std::array<Vec2, 8> polygon;
        std::size_t vertices = 0;
        for (int k = 0; k < 8; ++k) {
            if (!(best_[k] > -std::numeric_limits<float>::infinity())) {
                out.insert(out.end(), points.begin(), points.end());
                return;
            }
            if (vertices == 0 || polygon[vertices - 1] != point_[k])
                polygon[vertices++] = point_[k];
        }
        while (vertices > 1 && polygon[0] == polygon[vertices - 1]) --vertices;
        if (vertices < 3) {
            out.insert(out.end(), points.begin(), points.end());
            return;
        }
        for (std::size_t k = 0; k < vertices; ++k) {
            const Vec2& p = polygon[k];
            const Vec2& q = polygon[(k + 1) % vertices];
            const double a = static_cast<double>(p.y()) - q.y();
            const double b = static_cast<double>(q.x()) - p.x();
            lines[count++] = {a, b, -(a * p.x() + b * p.y())};
        }
        for (const Vec2& p : points) {
            bool inside = true;
            for (std::size_t k = 0; k < count && inside; ++k)
                inside = lines[k][0] * p.x() + lines[k][1] * p.y() + lines[k][2] > 0.0;
            if (!inside) out.push_back(p);
        }
    }

  private:
    // Counter-clockwise: +x, +x+y, +y, -x+y, -x, -x-y, -y, +x-y.
    static constexpr float kDirections[8][2] = {{1, 0},  {1, 1},   {0, 1},  {-1, 1},
                                                {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
    std::array<float, 8> best_ = {
        -std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
        -std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
        -std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
        -std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()};
    std::array<Vec2, 8> point_{};
};

/// Andrew's monotone chain: the convex hull counter-clockwise, without collinear vertices.
std::vector<Vec2> monotone_chain(std::vector<Vec2> points);

/// The convex hull of `points` (the octagon filter, then the monotone chain).
std::vector<Vec2> convex_hull(std::span<const Vec2> points);

/// Whether q lies in the convex counter-clockwise polygon `hull` (at least 3 vertices;
/// boundary included), in O(log n).
bool inside_convex(std::span<const Vec2> hull, const Vec2& q);

/// A convex counter-clockwise polygon with a grid that answers most point tests in O(1): a cell
/// of a 64 x 64 grid over the polygon's bounding box is "deep" when it and its eight neighbours
/// have all their corners inside (by inside_convex); a point in a deep cell is at least a cell
/// width inside, so it is inside whatever the rounding. Other points take inside_convex().
/// contains(q) == inside_convex(polygon, q) for every q.
class ConvexRegion {
  public:
    /// `polygon`: at least 3 vertices, counter-clockwise.
    explicit ConvexRegion(std::vector<Vec2> polygon);
    bool contains(const Vec2& q) const;
    /// Whether q lies inside the polygon or within `margin` of it (of its edges).
    bool contains(const Vec2& q, float margin) const;
    const std::vector<Vec2>& polygon() const { return polygon_; }

  private:
    static constexpr int kCells = 64;
    std::vector<Vec2> polygon_;
    Vec2 lo_ = Vec2::Zero(), hi_ = Vec2::Zero();  // bounding box
    float x0_ = 0.0f, y0_ = 0.0f, scale_x_ = 0.0f, scale_y_ = 0.0f;
    std::vector<std::uint8_t> deep_;  // kCells x kCells, row-major by y
};

struct Rectangle {
    float length = 0.0f, width = 0.0f;
    Vec2 length_axis = Vec2::UnitX();
};

/// Smallest-area rectangle holding a strictly convex counter-clockwise polygon: one side lies
/// on a hull edge (Freeman & Shapira 1975); rotating calipers (Toussaint 1983) find the extreme
/// vertices of every edge in O(n) overall.
Rectangle min_area_rectangle(std::span<const Vec2> hull);

}  // namespace esf::detail
