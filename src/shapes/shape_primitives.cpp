#include "shapes/shape_primitives.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "core/fnv1a.hpp"
#include "core/splitmix64.hpp"

namespace esf::shapes {

namespace {

constexpr double kPi = std::numbers::pi;

/// The first output of a SplitMix64 generator started at `x`.
std::uint64_t splitmix64(std::uint64_t x) { return detail::splitmix64(x); }

Vec3 centroid(const Ring& ring) {
    Vec3 sum = Vec3::Zero();
    for (const Vec3& p : ring) sum += p;
    return sum / static_cast<double>(ring.size());
}

int to_index(std::size_t i) { return static_cast<int>(i); }

/// Makes a single closed component face outwards.
void orient_outwards(Surface& surface) {
    if (surface.signed_volume() < 0.0) surface.flip();
}

}  // namespace

// ---- Rng -------------------------------------------------------------------------------------

std::uint64_t Rng::next() { return detail::splitmix64(state_); }

double Rng::uniform() { return detail::splitmix64_uniform(state_); }

double Rng::uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

int Rng::integer(int lo, int hi) {
    const auto span = static_cast<std::uint64_t>(static_cast<std::int64_t>(hi) - lo + 1);
    return lo + static_cast<int>(next() % span);
}

bool Rng::chance(double probability) { return uniform() < probability; }

std::uint64_t model_seed(std::uint64_t seed, std::string_view category, int index) {
    const std::uint64_t name_hash = detail::fnv1a(category);
    std::uint64_t x = splitmix64(seed);
    x = splitmix64(x ^ name_hash);
    return splitmix64(x ^ static_cast<std::uint64_t>(static_cast<std::uint32_t>(index)));
}

// ---- Surface ---------------------------------------------------------------------------------

void Surface::append(const Surface& other) {
    const int base = to_index(vertices.size());
    vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
    triangles.reserve(triangles.size() + other.triangles.size());
    for (const Eigen::Vector3i& t : other.triangles)
        triangles.push_back(t + Eigen::Vector3i::Constant(base));
}

Surface& Surface::transform(const Eigen::Affine3d& motion) {
    assert(motion.linear().determinant() > 0.0);
    for (Vec3& v : vertices) v = motion * v;
    return *this;
}

Surface& Surface::translate(const Vec3& offset) {
    for (Vec3& v : vertices) v += offset;
    return *this;
}

double Surface::signed_volume() const {
    double six_volume = 0.0;
    for (const Eigen::Vector3i& t : triangles)
        six_volume += vertices[static_cast<std::size_t>(t[0])].dot(
            vertices[static_cast<std::size_t>(t[1])].cross(
                vertices[static_cast<std::size_t>(t[2])]));
    return six_volume / 6.0;
}

void Surface::flip() {
    for (Eigen::Vector3i& t : triangles) std::swap(t[1], t[2]);
}

Vec3 Surface::min_corner() const {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
    for (const Vec3& v : vertices) lo = lo.cwiseMin(v);
    return lo;
}

Vec3 Surface::max_corner() const {
    Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());
    for (const Vec3& v : vertices) hi = hi.cwiseMax(v);
    return hi;
}

Mesh Surface::to_mesh() const {
    Mesh mesh;
    mesh.vertices.reserve(vertices.size());
    for (const Vec3& v : vertices) mesh.vertices.push_back(v.cast<float>());
    mesh.triangles = triangles;
    return mesh;
}

// ---- Lofts -----------------------------------------------------------------------------------

Surface loft(const std::vector<Ring>& rings, LoftEnds ends, std::optional<Vec3> start_cap,
             std::optional<Vec3> end_cap) {
    if (rings.size() < 2 || rings.front().size() < 3)
        throw std::invalid_argument("loft: needs at least 2 rings of at least 3 points");
    const std::size_t n = rings.front().size();
    Surface s;
    for (const Ring& ring : rings) {
        if (ring.size() != n) throw std::invalid_argument("loft: rings differ in size");
        s.vertices.insert(s.vertices.end(), ring.begin(), ring.end());
    }
    const auto id = [n](std::size_t ring, std::size_t j) { return to_index(ring * n + j % n); };
    const std::size_t strips = ends == LoftEnds::kLoop ? rings.size() : rings.size() - 1;
    for (std::size_t i = 0; i < strips; ++i) {
        const std::size_t next = (i + 1) % rings.size();
        for (std::size_t j = 0; j < n; ++j) {
            const int a = id(i, j), b = id(i, j + 1), c = id(next, j + 1), d = id(next, j);
            s.triangles.emplace_back(a, b, c);
            s.triangles.emplace_back(a, c, d);
        }
    }
    if (ends == LoftEnds::kCaps) {
        const std::size_t last = rings.size() - 1;
        const int first_centre = to_index(s.vertices.size());
        s.vertices.push_back(start_cap.value_or(centroid(rings.front())));
        const int last_centre = to_index(s.vertices.size());
        s.vertices.push_back(end_cap.value_or(centroid(rings.back())));
        for (std::size_t j = 0; j < n; ++j) {
            s.triangles.emplace_back(first_centre, id(0, j + 1), id(0, j));
            s.triangles.emplace_back(last_centre, id(last, j), id(last, j + 1));
        }
    }
    orient_outwards(s);
    return s;
}

Surface revolve(const Path2& profile, int segments, const RingDeform& deform) {
    if (profile.size() < 2 || segments < 3)
        throw std::invalid_argument("revolve: needs 2 profile points and 3 segments");
    constexpr double kOnAxis = 1e-9;
    Path2 points = profile;
    const bool is_loop = (points.front() - points.back()).norm() < 1e-12;
    if (is_loop) points.pop_back();
    // Axis points at the ends are poles: they become cap centres, not rings.
    std::optional<Vec3> start_cap, end_cap;
    std::size_t first = 0, last = points.size();
    if (!is_loop) {
        start_cap = Vec3(0.0, 0.0, points.front().y());
        end_cap = Vec3(0.0, 0.0, points.back().y());
        if (points.front().x() <= kOnAxis) ++first;
        if (points.back().x() <= kOnAxis) --last;
    }
    if (last < first + (is_loop ? 3 : 2))
        throw std::invalid_argument("revolve: profile has too few points off the axis");
    std::vector<Ring> rings;
    for (std::size_t i = first; i < last; ++i) {
        if (points[i].x() <= kOnAxis)
            throw std::invalid_argument("revolve: only the profile's ends may touch the axis");
        Ring ring;
        ring.reserve(static_cast<std::size_t>(segments));
        for (int j = 0; j < segments; ++j) {
            const double angle = 2.0 * kPi * j / segments;
            Vec3 p(points[i].x() * std::cos(angle), points[i].x() * std::sin(angle), points[i].y());
            if (deform) p = deform(p, i, angle);
            ring.push_back(p);
        }
        rings.push_back(std::move(ring));
    }
    return loft(rings, is_loop ? LoftEnds::kLoop : LoftEnds::kCaps, start_cap, end_cap);
}

Surface tube(const std::vector<TubeStation>& stations, const Path2& section,
             const Vec3& normal_hint, double start_dome, double end_dome) {
    if (stations.size() < 2 || section.size() < 3)
        throw std::invalid_argument("tube: needs 2 stations and a section of 3 points");
    const std::size_t count = stations.size();
    std::vector<Vec3> tangents(count);
    for (std::size_t i = 0; i < count; ++i) {
        const Vec3& before = stations[i == 0 ? 0 : i - 1].centre;
        const Vec3& after = stations[i + 1 == count ? i : i + 1].centre;
        tangents[i] = (after - before).normalized();
    }
    // Rotation-minimising frames by projecting the previous normal (smooth spines only).
    Vec3 normal = normal_hint - normal_hint.dot(tangents[0]) * tangents[0];
    if (normal.norm() < 1e-9) normal = tangents[0].unitOrthogonal();
    normal.normalize();
    std::vector<Ring> rings;
    rings.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
        normal = (normal - normal.dot(tangents[i]) * tangents[i]).normalized();
        const Vec3 binormal = tangents[i].cross(normal);
        Ring ring;
        ring.reserve(section.size());
        for (const Vec2& q : section)
            ring.push_back(stations[i].centre + q.x() * stations[i].u_scale * normal +
                           q.y() * stations[i].v_scale * binormal);
        rings.push_back(std::move(ring));
    }
    const auto size = [](const TubeStation& s) { return std::max(s.u_scale, s.v_scale); };
    const Vec3 start =
        stations.front().centre - start_dome * size(stations.front()) * tangents.front();
    const Vec3 end = stations.back().centre + end_dome * size(stations.back()) * tangents.back();
    return loft(rings, LoftEnds::kCaps, start, end);
}

Surface stack(const std::vector<Slice>& slices, int per_corner, int per_side) {
    std::vector<Ring> rings;
    rings.reserve(slices.size());
    for (const Slice& s : slices)
        rings.push_back(place(rounded_rect(s.half_x, s.half_y, s.corner, per_corner, per_side),
                              Vec3(s.cx, s.cy, s.z), Vec3::UnitX(), Vec3::UnitY()));
    return loft(rings);
}

std::vector<Slice> rounded_box_slices(const Vec3& half, double corner, double bevel,
                                      int bevel_steps) {
    std::vector<Slice> slices;
    const auto add = [&](double z, double inset) {
        slices.push_back({z, half.x() - inset, half.y() - inset, corner - inset, 0.0, 0.0});
    };
    if (bevel <= 0.0 || bevel_steps < 1) {
        add(0.0, 0.0);
        add(2.0 * half.z(), 0.0);
        return slices;
    }
    // Quarter circles from the bottom face (inset by the bevel) up to the side, and back in.
    for (int k = 0; k <= bevel_steps; ++k) {
        const double a = 0.5 * kPi * k / bevel_steps;
        add(bevel * (1.0 - std::cos(a)), bevel * (1.0 - std::sin(a)));
    }
    for (int k = bevel_steps; k >= 0; --k) {
        const double a = 0.5 * kPi * k / bevel_steps;
        add(2.0 * half.z() - bevel * (1.0 - std::cos(a)), bevel * (1.0 - std::sin(a)));
    }
    return slices;
}

// ---- 2-D paths -------------------------------------------------------------------------------

Path2 rounded_rect(double half_x, double half_y, double corner, int per_corner, int per_side) {
    const double r = std::clamp(corner, kMinCorner, 0.95 * std::min(half_x, half_y));
    const double cx = half_x - r, cy = half_y - r;
    const Vec2 centres[4] = {{cx, cy}, {-cx, cy}, {-cx, -cy}, {cx, -cy}};
    Path2 path;
    for (int k = 0; k < 4; ++k) {
        const Path2 corner_arc =
            arc(centres[k], r, 0.5 * kPi * k, 0.5 * kPi * (k + 1), per_corner + 1);
        path.insert(path.end(), corner_arc.begin(), corner_arc.end());
        const Vec2 from = corner_arc.back();
        const Vec2 to = centres[(k + 1) % 4] +
                        r * Vec2(std::cos(0.5 * kPi * (k + 1)), std::sin(0.5 * kPi * (k + 1)));
        for (int m = 1; m <= per_side; ++m) path.push_back(from + (to - from) * m / (per_side + 1));
    }
    return path;
}

Path2 superellipse(double a, double b, double exponent, int count) {
    Path2 path;
    path.reserve(static_cast<std::size_t>(count));
    const double power = 2.0 / exponent;
    for (int k = 0; k < count; ++k) {
        const double t = 2.0 * kPi * k / count;
        const double c = std::cos(t), s = std::sin(t);
        path.emplace_back(a * std::copysign(std::pow(std::abs(c), power), c),
                          b * std::copysign(std::pow(std::abs(s), power), s));
    }
    return path;
}

Path2 bezier(const Vec2& p0, const Vec2& p1, const Vec2& p2, const Vec2& p3, int count) {
    Path2 path;
    for (int k = 0; k < count; ++k) {
        const double t = static_cast<double>(k) / (count - 1), u = 1.0 - t;
        path.push_back(u * u * u * p0 + 3.0 * u * u * t * p1 + 3.0 * u * t * t * p2 +
                       t * t * t * p3);
    }
    return path;
}

Path2 arc(const Vec2& centre, double radius, double a0, double a1, int count) {
    Path2 path;
    for (int k = 0; k < count; ++k) {
        const double a = lerp(a0, a1, static_cast<double>(k) / (count - 1));
        path.push_back(centre + radius * Vec2(std::cos(a), std::sin(a)));
    }
    return path;
}

Path2 segment(const Vec2& a, const Vec2& b, int count) {
    Path2 path;
    for (int k = 0; k < count; ++k) path.push_back(a + (b - a) * k / (count - 1));
    return path;
}

void extend(Path2& path, const Path2& piece) {
    auto begin = piece.begin();
    if (!path.empty() && begin != piece.end() && (*begin - path.back()).norm() < kSamePoint)
        ++begin;
    path.insert(path.end(), begin, piece.end());
}

Path2 offset(const Path2& path, double distance) {
    Path2 result;
    result.reserve(path.size());
    for (std::size_t i = 0; i < path.size(); ++i) {
        const Vec2& before = path[i == 0 ? 0 : i - 1];
        const Vec2& after = path[i + 1 == path.size() ? i : i + 1];
        const Vec2 t = (after - before).normalized();
        result.push_back(path[i] + distance * Vec2(-t.y(), t.x()));
    }
    return result;
}

Ring place(const Path2& loop, const Vec3& origin, const Vec3& u_axis, const Vec3& v_axis) {
    Ring ring;
    ring.reserve(loop.size());
    for (const Vec2& q : loop) ring.push_back(origin + q.x() * u_axis + q.y() * v_axis);
    return ring;
}

double smoothstep(double edge0, double edge1, double x) {
    const double t = std::clamp((x - edge0) / (edge1 - edge0), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

double lerp(double a, double b, double t) { return a + (b - a) * t; }

}  // namespace esf::shapes
