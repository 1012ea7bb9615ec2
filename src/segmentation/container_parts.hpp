#pragma once
// Joins the inside of an open container to its outside. A cup, a bowl or a pot seen from above
// shows its outer wall in front and its inner wall and bottom behind the rim; the two meet only
// along the rim, where they are too thin to give patches (so convexity grouping keeps them
// apart). Two objects standing on a table never share floor space, so a group lying within
// another group's round footprint belongs to it:
//   - the outer group's points, projected on the table plane, fit a circle (a vertical wall):
//     radius in [min_radius, max_radius], RMS radial residual <= max_residual x radius;
//   - at least `min_inside` of the inner group's projected points lie within the radius plus
//     `margin`, and the inner group does not rise above the outer one's top by more than
//     `margin` (a box standing behind a can is outside its circle, one standing on it above).
// And two groups whose upper parts lie on one circle are parts of one round wall (below).
// Groups of fewer than min_points points take no part. `component` is renumbered in order of
// first appearance.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "esf/segmentation/segmentation.hpp"

namespace esf::detail {

struct ContainerPartsOptions {
    float min_radius = 0.02f;    ///< m
    float max_radius = 0.20f;    ///< m
    float max_residual = 0.15f;  ///< of the radius
    float margin = 0.01f;        ///< m
    float min_inside = 0.9f;     ///< share of the inner group's points
    /// Two groups whose upper parts (points above rim_band x their top height) lie together on
    /// one circle (RMS residual <= max_shared_residual x radius) are two parts of one round
    /// wall: the outside and inside of a bowl, or an inside cut in two.
    /// Each group's upper part must fit that circle too, whose radius is at most
    /// max_shared_radius, and the two upper parts must be near each other.
    float rim_band = 0.6f;
    float max_shared_residual = 0.08f;
    float max_shared_radius = 0.12f;  ///< m
    float max_shared_gap = 0.02f;     ///< m between the upper parts' bounding boxes
    std::uint32_t min_points = 200;
};

/// `points`: the candidates (one per entry of `component`); `up` and `offset`: the table plane,
/// height(p) = up . p + offset, |up| = 1.
void join_container_parts(std::span<const Eigen::Vector3f> points,
                          std::vector<std::uint32_t>& component, const Eigen::Vector3f& up,
                          float offset, const ContainerPartsOptions& options = {});

/// The floor of an open container (organised frames): a bowl's, cup's or plate's inner bottom
/// lies a few millimetres above the table, below min_height, and was taken for table. A cluster
/// whose upper part (its points above rim_band x its top height; at least min_points / 4 of them,
/// of a cluster of min_points or more) fits a round circle as above takes in every pixel of its
/// image bounding box that no cluster holds, lies less than min_height from the plane, on the
/// plane within the circle's radius less `margin` of its centre, and in the image between pixels
/// of the cluster to its left and right, above and below (seen through the opening: the table
/// under an overhanging rim has none of the object below it). `points`: the frame (width x height,
/// row-major); cluster indices are pixel indices and stay ascending. Returns the points taken in.
std::size_t join_container_floors(std::span<const Eigen::Vector3f> points, std::uint32_t width,
                                  const Plane& plane, float min_height,
                                  std::vector<Cluster>& clusters,
                                  const ContainerPartsOptions& options = {});

}  // namespace esf::detail
