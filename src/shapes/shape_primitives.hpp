#pragma once
// Building blocks of the procedural shape generator (esf/shape_generator.hpp): closed,
// consistently oriented triangle surfaces made by lofting rings of points — surfaces of
// revolution, swept tubes, stacks of rounded rectangles. A shape is a union of such components,
// each closed on its own; components may overlap (no booleans), which suits depth rendering.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <optional>
#include <string_view>
#include <vector>

#include "esf/mesh/mesh.hpp"

namespace esf::shapes {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Path2 = std::vector<Vec2>;  ///< a 2-D polyline: (x, y) or a profile's (r, z)
using Ring = std::vector<Vec3>;   ///< a closed loop of points, the last joined to the first

/// SplitMix64 (Steele et al. 2014): tiny, fast, and the same numbers on every platform (unlike
/// std::uniform_real_distribution, whose mapping the standard leaves to the library).
class Rng {
  public:
    explicit Rng(std::uint64_t seed) : state_(seed) {}
    std::uint64_t next();
    double uniform();                      ///< [0, 1)
    double uniform(double lo, double hi);  ///< [lo, hi)
    int integer(int lo, int hi);           ///< [lo, hi], both included
    bool chance(double probability);

  private:
    std::uint64_t state_;
};

/// The seed of model `index` of `category`: a hash of (seed, category, index).
std::uint64_t model_seed(std::uint64_t seed, std::string_view category, int index);

/// A triangle surface in double precision, made of one or more closed components.
struct Surface {
    std::vector<Vec3> vertices;
    std::vector<Eigen::Vector3i> triangles;  ///< counter-clockwise seen from outside

    void append(const Surface& other);
    /// Applies a rigid motion or a uniform positive scale (orientation-preserving maps only).
    Surface& transform(const Eigen::Affine3d& motion);
    Surface& translate(const Vec3& offset);
    double signed_volume() const;  ///< divergence theorem; > 0 when normals point outwards
    void flip();                   ///< reverses every triangle
    Vec3 min_corner() const;
    Vec3 max_corner() const;
    Mesh to_mesh() const;
};

enum class LoftEnds { kCaps, kLoop };

/// Joins consecutive rings (all of the same size) by quads split into two triangles. With kCaps
/// the first and last rings are closed by fans to `start_cap` / `end_cap` (default: the ring's
/// centroid); with kLoop the last ring is joined back to the first (a torus-like solid). The
/// result is one closed component, oriented outwards.
Surface loft(const std::vector<Ring>& rings, LoftEnds ends = LoftEnds::kCaps,
             std::optional<Vec3> start_cap = std::nullopt,
             std::optional<Vec3> end_cap = std::nullopt);

/// Moves a point of a surface of revolution: (point, profile index, angle) -> new point.
using RingDeform = std::function<Vec3(const Vec3&, std::size_t, double)>;

/// Surface of revolution about the z axis of a profile of (r, z) points, `segments` around.
/// Profile ends on the axis (r = 0) become poles; a profile whose last point equals its first is
/// a loop (torus-like); other ends are closed by flat discs. `deform` may move each ring point.
Surface revolve(const Path2& profile, int segments, const RingDeform& deform = {});

/// One cross-section of a swept tube: centre on the spine and the section's scale along the
/// frame's normal (u) and binormal (v).
struct TubeStation {
    Vec3 centre;
    double u_scale = 1.0;
    double v_scale = 1.0;
};

/// Sweeps a closed 2-D section (unit size, counter-clockwise) along the stations with rotation-
/// minimising frames; the first normal is `normal_hint` made perpendicular to the spine. Ends are
/// capped by fans to the end centre moved outwards along the spine by dome * the end's size.
Surface tube(const std::vector<TubeStation>& stations, const Path2& section,
             const Vec3& normal_hint, double start_dome = 0.0, double end_dome = 0.0);

/// A horizontal slice of a stack: rounded rectangle centred at (cx, cy) at height z.
struct Slice {
    double z = 0.0;
    double half_x = 0.0;
    double half_y = 0.0;
    double corner = 0.0;  ///< corner radius, clamped to [kMinCorner, 0.95 * min(half_x, half_y)]
    double cx = 0.0;
    double cy = 0.0;
};

/// Lofts rounded-rectangle slices (bottom to top) into one closed solid with flat caps.
Surface stack(const std::vector<Slice>& slices, int per_corner = 4, int per_side = 3);

/// Slices of a rounded box [-h, h] with vertical-edge radius `corner` and a `bevel` rounding the
/// top and bottom edges (z from 0 to 2 h.z()).
std::vector<Slice> rounded_box_slices(const Vec3& half, double corner, double bevel,
                                      int bevel_steps = 3);

// ---- 2-D paths -------------------------------------------------------------------------------

inline constexpr double kMinCorner = 2e-4;

/// Counter-clockwise rounded rectangle of 4 * (per_corner + 1 + per_side) points, starting at
/// the +x+y corner's arc; the same counts give corresponding points whatever the sizes, so such
/// rectangles loft well. `corner` is clamped to [kMinCorner, 0.95 * min(half_x, half_y)].
Path2 rounded_rect(double half_x, double half_y, double corner, int per_corner, int per_side);
/// Counter-clockwise superellipse |x/a|^n + |y/b|^n = 1 with `count` points (n = 2: ellipse).
Path2 superellipse(double a, double b, double exponent, int count);
/// Cubic Bezier curve, `count` points including both ends.
Path2 bezier(const Vec2& p0, const Vec2& p1, const Vec2& p2, const Vec2& p3, int count);
/// Circular arc from angle a0 to a1 (radians), `count` points including both ends.
Path2 arc(const Vec2& centre, double radius, double a0, double a1, int count);
/// Straight segment with `count` points including both ends.
Path2 segment(const Vec2& a, const Vec2& b, int count);
/// Points closer than this (metres) are the same point when paths are joined.
inline constexpr double kSamePoint = 1e-6;
/// Appends `piece` to `path`, dropping its first point when it repeats the path's last (closer
/// than kSamePoint).
void extend(Path2& path, const Path2& piece);
/// Offsets each point of an open polyline by `distance` along its left normal.
Path2 offset(const Path2& path, double distance);
/// Lifts a 2-D loop into 3-D: origin + x * u_axis + y * v_axis.
Ring place(const Path2& loop, const Vec3& origin, const Vec3& u_axis, const Vec3& v_axis);

/// Smooth step 0 -> 1 between edge0 and edge1 (cubic Hermite).
double smoothstep(double edge0, double edge1, double x);
double lerp(double a, double b, double t);

}  // namespace esf::shapes
