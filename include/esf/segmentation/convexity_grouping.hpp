#pragma once
// Groups surface patches into objects by local convexity (LCCP: Stein, Schoeler, Papon &
// Woergoetter, "Object partitioning using local convexity", CVPR 2014). Objects on a table are
// convex where they are whole and meet their neighbours in concave creases: where a box stands on
// another, where two cans touch, where a cup leans on a box. So two adjacent patches belong to
// one object when the surface between them is convex (or nearly flat), and objects are the
// connected components of that relation.
//
// For adjacent patches with centroids c1, c2, unit normals n1, n2 and d = (c1 - c2) / |c1 - c2|:
//   - smooth: the angle between n1 and n2 is below `concavity_tolerance` (noise makes flat
//     surfaces look slightly concave half of the time, and the inside of a bowl or a cup turns
//     by 10-20 degrees between patches a centimetre apart, while objects that touch meet in
//     creases of 45 degrees or more: 90 where a box stands on a box);
//   - convex: (n1 - n2) . d > 0 (the normals open away from each other), and the connection is
//     not singular: the angle between d and the crease direction n1 x n2 is at least
//     `sanity_angle` (LCCP's sanity criterion: patches touching along the crease only at a
//     point of it are no evidence of convexity), except where the normals are nearly
//     opposite (within `lip_angle` of 180 degrees: the two sides of a thin wall at its rim);
//   - otherwise concave: the edge is cut.
// The normals are first smoothed over smooth neighbours (`smoothing_passes`), so that depth
// noise on a curved wall does not fake a crease. Patches without a normal join nothing at first.
// Segments smaller than `min_segment_points` then join, smallest first, the neighbouring segment
// they share the most contacts with (LCCP's merging of small segments): a patch torn by noise or a
// sliver along a crease goes to one side. Segments are numbered in order of their first patch; the
// result is deterministic.

#include <cstdint>
#include <vector>

#include "esf/segmentation/surface_patches.hpp"

namespace esf {

struct ConvexityOptions {
    float concavity_tolerance_deg = 25.0f;  ///< [0, 90)
    float sanity_angle_deg = 60.0f;         ///< [0, 90]
    /// Convex joins of patches whose normals are within this of opposite are a thin wall's rim
    /// and join without the sanity test; [0, 90], 0 = never.
    float lip_angle_deg = 30.0f;
    std::uint32_t min_segment_points = 150;
    /// Passes of bilateral normal smoothing before the test: each patch's normal becomes the
    /// point-weighted mean of its own and its smooth neighbours' (those within the concavity
    /// tolerance), which damps sensor noise but keeps creases; 0 = none.
    int smoothing_passes = 1;
};

/// Throws std::invalid_argument when an option is out of range.
void validate(const ConvexityOptions& options);

/// Whether two adjacent patches join (smooth or convex, as above). False when either has no
/// normal.
bool convex_connection(const SurfacePatch& a, const SurfacePatch& b,
                       const ConvexityOptions& options = {});

/// The segment of each patch of `graph`.
std::vector<std::uint32_t> convex_segments(const PatchGraph& graph,
                                           const ConvexityOptions& options = {});

}  // namespace esf
