#pragma once
// Joins the visible parts of one object that an occluder in front of it cuts apart (a box seen
// on both sides of a can standing before it): no grouping by connectivity can join them, since
// nothing of the object links the parts in the image. Two groups of an organised frame are one
// object when
//   - both are planar (RMS distance to their least-squares plane <= max_plane_rms),
//   - their planes agree: normals within max_normal_angle_deg, each centroid within
//     max_plane_offset of the other's plane, and
//   - every pixel on the image line between their image centroids is one of theirs, or holds a
//     point at least `min_occluder_gap` in front of their common plane along the pixel's ray
//     (the occluder); at most max_invalid_share of the pixels may be invalid (NaN).
// Groups of fewer than min_points points take no part. `component` (one entry per candidate)
// is renumbered in order of first appearance.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace esf::detail {

struct OccludedPartsOptions {
    float max_plane_rms = 0.005f;          ///< m
    float max_normal_angle_deg = 15.0f;    ///< degrees
    float max_plane_offset = 0.015f;       ///< m
    float min_occluder_gap = 0.01f;        ///< m
    float max_invalid_share = 0.2f;        ///< of the line's pixels
    std::uint32_t min_points = 200;
};

void join_occluded_parts(std::span<const Eigen::Vector3f> points, std::uint32_t width,
                         std::uint32_t height, std::span<const std::uint32_t> candidates,
                         std::vector<std::uint32_t>& component, const Eigen::Vector3f& viewpoint,
                         const OccludedPartsOptions& options = {});

}  // namespace esf::detail
