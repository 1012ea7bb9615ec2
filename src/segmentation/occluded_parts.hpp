#pragma once
// Joins the visible parts of one object that an occluder in front of it cuts apart (a box seen
// on both sides of a can standing before it): no grouping by connectivity can join them, since
// nothing of the object links the parts in the image. Two groups of an organised frame are one
// object when, on the image line between their image centroids, the pixels between the last
// pixel of the one and the first pixel of the other
//   - all belong to other groups (an object, not the table or nothing), at most
//     `max_invalid_share` of them invalid (NaN), and
//   - all lie at least `min_occluder_gap` nearer to the sensor than both ends (the occluder),
// and the ranges of the two ends differ by at most max_end_gap + max_end_slope x their distance
// (one surface continues behind the occluder, facing the sensor or turned away by up to about
// 45 degrees), and both groups reach the same height above the table within
// `max_top_difference` (the parts of one box or can end at its top). The invalid pixels allowed
// are the sensor's shadow beside the occluder (a structured-light sensor sees no depth where
// the occluder hides its projector).
// Groups of fewer than min_points points take no part. `component` (one entry per candidate)
// is renumbered in order of first appearance.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace esf::detail {

struct OccludedPartsOptions {
    float min_occluder_gap = 0.02f;    ///< m
    float max_end_gap = 0.02f;         ///< m
    float max_end_slope = 1.0f;        ///< range difference per metre between the ends
    float max_top_difference = 0.02f;  ///< m
    float max_invalid_share = 0.4f;    ///< of the pixels between the parts
    std::uint32_t min_points = 200;
};

/// `up` and `offset`: the table plane, height(p) = up . p + offset.
void join_occluded_parts(std::span<const Eigen::Vector3f> points, std::uint32_t width,
                         std::uint32_t height, std::span<const std::uint32_t> candidates,
                         std::vector<std::uint32_t>& component, const Eigen::Vector3f& viewpoint,
                         const Eigen::Vector3f& up, float offset,
                         const OccludedPartsOptions& options = {});

}  // namespace esf::detail
