#pragma once
// Camera positions for synthetic views: the face centres of a subdivided icosahedron (the
// "tessellated view sphere" of Wohlkinger & Vincze 2011, Sec. IV), and look-at poses.

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

namespace esf {

inline constexpr int kMaxViewSphereLevel = 6;  ///< 81920 views

/// Number of views of a level: 20 * 4^level (0 -> 20, 1 -> 80, 2 -> 320).
std::size_t view_count(int level);

/// Unit vectors from the object's centre towards the cameras: an icosahedron whose triangles are
/// split `level` times into four (edge midpoints pushed onto the unit sphere), one camera per
/// final triangle at its centroid, normalised onto the sphere. The order is fixed: the 20
/// icosahedron faces in turn, each child list (corner a, corner b, corner c, middle) depth first.
/// Throws std::invalid_argument unless 0 <= level <= kMaxViewSphereLevel.
std::vector<Eigen::Vector3d> view_sphere(int level);

/// The world -> camera transform of a camera at `eye` looking at `target` (camera frame: x right,
/// y down, z forward). Image up (-y) is the projection of world +z, or of world +y when the view
/// direction is within about 8 degrees of the z axis (|forward.z| > 0.99), so poses are
/// reproducible. Throws std::invalid_argument when eye == target or either is not finite.
Eigen::Isometry3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);

}  // namespace esf
