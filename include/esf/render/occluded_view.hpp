#pragma once
// A rendered view with part of it hidden, the way a nearer object hides part of another on a
// cluttered table: the points on one side of a straight edge across the image are dropped.
// Training describes each view a few times so (TrainingOptions::occlusions), so that an object
// seen behind another finds the views of its model with the same part missing.
//
// The edge runs across the image at a given direction; the points are ordered by their image
// position along that direction, x / z cos(angle) + y / z sin(angle) (the pinhole projection
// up to the intrinsics, so that the cut is a straight line in the image whatever the camera),
// and the first `fraction` of them (ties: the earlier point first) are dropped. The others keep
// their order.

#include <Eigen/Core>
#include <cstdint>
#include <span>

#include "esf/core/point_cloud.hpp"

namespace esf {

/// The share of a view's points an occluded copy hides is drawn from [min, max].
inline constexpr double kMinOccludedFraction = 0.2;
inline constexpr double kMaxOccludedFraction = 0.5;

/// The points of a view (camera frame, z > 0) left when the edge at `angle` (radians, from the
/// image's x axis towards its y axis) hides floor(fraction x n) of the n points from the side
/// the direction points away from. Throws std::invalid_argument for a fraction outside [0, 1],
/// an angle that is not finite or a point that is not finite or not in front of the camera.
Points occlude_view(std::span<const Eigen::Vector3f> points, double angle, double fraction);

/// The edge of occluded copy `copy` of a view whose descriptor seed is `view_seed`: an angle
/// uniform in [0, 2 pi) and a fraction uniform in [kMinOccludedFraction, kMaxOccludedFraction],
/// drawn with the project's SplitMix64 from the seed and the copy's number alone.
struct OcclusionEdge {
    double angle = 0.0;
    double fraction = 0.0;
};
OcclusionEdge occlusion_edge(std::uint64_t view_seed, std::uint32_t copy);

}  // namespace esf
