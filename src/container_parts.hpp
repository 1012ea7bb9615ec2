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
// Groups of fewer than min_points points take no part. `component` is renumbered in order of
// first appearance.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace esf::detail {

struct ContainerPartsOptions {
    float min_radius = 0.02f;    ///< m
    float max_radius = 0.20f;    ///< m
    float max_residual = 0.15f;  ///< of the radius
    float margin = 0.01f;        ///< m
    float min_inside = 0.9f;     ///< share of the inner group's points
    std::uint32_t min_points = 200;
};

/// `points`: the candidates (one per entry of `component`); `up` and `offset`: the table plane,
/// height(p) = up . p + offset, |up| = 1.
void join_container_parts(std::span<const Eigen::Vector3f> points,
                          std::vector<std::uint32_t>& component, const Eigen::Vector3f& up,
                          float offset, const ContainerPartsOptions& options = {});

}  // namespace esf::detail
