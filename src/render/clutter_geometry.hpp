#pragma once
// The geometry of cluttered table scenes (clutter_layout.cpp, clutter_scene.cpp): footprints of
// posed models as 2-D convex hulls on the table, their overlaps and distances, the shape of a
// model (round, boxy) and the bodies placed on the table.

#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

#include "core/convex_hull_2d.hpp"
#include "esf/mesh/mesh.hpp"

namespace esf::detail {

/// A footprint: a convex polygon in the table plane, counter-clockwise.
using Hull = std::vector<Vec2>;

/// The area of a convex polygon.
double polygon_area(const Hull& hull);

/// Whether two convex polygons (counter-clockwise, at least 3 vertices) overlap (separating
/// axis test).
bool polygons_overlap(const Hull& a, const Hull& b);

/// The distance between two convex polygons; 0 when they overlap.
double polygon_distance(const Hull& a, const Hull& b);

/// Points on the surface of a model whose convex hull is (nearly) the model's: the extreme vertex
/// in 162 directions and every vertex of the upright footprint's hull.
std::vector<Eigen::Vector3d> support_points(const Mesh& mesh);

struct ModelShape {
    std::vector<Eigen::Vector3d> support;
    bool round = false;
    bool boxy = false;
    double height = 0.0;
};

/// The shape of a model: its support points, whether its footprint is round (a disc) or boxy.
ModelShape analyse(const Mesh& mesh);

// A posed model on the table.
struct Body {
    std::size_t model = 0;
    double size = 1.0;  // the model's metres times this (ClutterOptions::size_spread)
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // sized model (metres) -> world
    Hull hull;                                               // world xy
    double zmin = 0.0, zmax = 0.0;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    double radius = 0.0;  // of the hull around centre
    int base = -1;        // the body it stands on
    std::string placement = "standing";

    void move(const Eigen::Vector3d& delta) {
        pose.pretranslate(delta);
        for (Vec2& v : hull) v += delta.head<2>().cast<float>();
        centre += delta.head<2>();
        zmin += delta.z();
        zmax += delta.z();
    }
};

// Whether two bodies take the same space: overlapping footprints and heights (touching tops
// and bottoms do not count); with `gap` > 0, footprints closer than `gap` count as overlapping.
bool collide(const Body& a, const Body& b, double gap);

/// The rotation by `angle` (radians) about `axis`.
Eigen::Matrix3d rotation_about(const Eigen::Vector3d& axis, double angle);

}  // namespace esf::detail
