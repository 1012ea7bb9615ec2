#pragma once
// Small surface patches and their adjacency: the nodes and edges that convexity grouping
// (esf/convexity_grouping.hpp) joins into objects. They play the part of the supervoxels of
// LCCP (Stein et al., "Object partitioning using local convexity", CVPR 2014), made much more
// cheaply:
//   - organised frames: the image is cut into square tiles of `tile_pixels`; inside a tile the
//     pixels that are depth-continuous with a 4-neighbour form one patch (a tile that holds an
//     occluding edge gives two or more patches, so no patch straddles a depth jump). Two
//     patches are adjacent when a pair of 4-neighbour pixels, one in each, is depth-continuous;
//     `contacts` counts those pairs;
//   - unorganised clouds: cubic voxels of side `voxel_size`; voxels that share a face, an edge
//     or a corner are adjacent (one contact).
// Each patch has its centroid and, when it holds at least `min_normal_points` points that are
// not collinear, the normal of its least-squares plane (the smallest principal axis of its
// points), oriented towards `viewpoint`.
//
// Depth continuity of two neighbouring pixels p and q seen from the viewpoint v:
//   | |p - v| - |q - v| |  <=  depth_jump + depth_jump_quadratic * |p - v|^2
// (the quadratic term follows the depth resolution of triangulation sensors, which falls with
// the square of the range).

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace esf {

struct SurfacePatchOptions {
    std::uint32_t tile_pixels = 6;        ///< organised: tile side in pixels, >= 2
    float voxel_size = 0.015f;            ///< unorganised: voxel side, > 0 (m)
    float depth_jump = 0.01f;             ///< m, >= 0
    float depth_jump_quadratic = 0.01f;   ///< 1/m, >= 0
    std::uint32_t min_normal_points = 6;  ///< >= 3
    Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();
};

struct SurfacePatch {
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    /// Unit normal towards the viewpoint; zero when the patch has too few or collinear points.
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();
    std::uint32_t points = 0;

    bool has_normal() const { return normal.squaredNorm() > 0.0f; }
};

struct PatchEdge {
    std::uint32_t a = 0, b = 0;  ///< patch ids, a < b
    std::uint32_t contacts = 0;  ///< neighbouring point pairs across the border (>= 1)
};

struct PatchGraph {
    std::vector<SurfacePatch> patches;
    /// The patch of each input point, in the order of the `members` given to the builder.
    std::vector<std::uint32_t> patch_of;
    /// Each adjacent pair once, sorted by (a, b).
    std::vector<PatchEdge> edges;
};

/// Throws std::invalid_argument when an option is out of range.
void validate(const SurfacePatchOptions& options);

/// Patches of the organised frame `points` (width x height, row-major) made of the points whose
/// indices are listed in `members` (ascending, each < width * height, finite).
PatchGraph image_patches(std::span<const Eigen::Vector3f> points, std::uint32_t width,
                         std::uint32_t height, std::span<const std::uint32_t> members,
                         const SurfacePatchOptions& options = {});

/// Voxel patches of the points listed in `members` (finite; any order).
PatchGraph voxel_patches(std::span<const Eigen::Vector3f> points,
                         std::span<const std::uint32_t> members,
                         const SurfacePatchOptions& options = {});

}  // namespace esf
