#pragma once
// Table-scene segmentation: the dominant plane is found by RANSAC, the points standing on it
// (above it on the sensor's side, inside its convex hull) are grouped into objects, and each
// object comes back at full resolution with its centroid and size.
//
// The steps (the table and prism after Rusu et al., "Close-range scene segmentation and
// reconstruction of 3D point cloud maps for mobile manipulation in domestic environments", IROS
// 2009; the grouping after Stein et al., "Object partitioning using local convexity", CVPR 2014):
//   1. plane fit on an even subsample of the finite points (every k-th point, k chosen so that
//      about `plane_samples` remain): RANSAC with per-hypothesis generators derived from
//      (seed, hypothesis index), then a least-squares refit to the sampled inliers;
//   2. the plane is oriented so that its normal points to the sensor (`viewpoint`), which decides
//      "above" in any frame (camera frame z forward, or y up / z towards the viewer); a plane
//      parallel to it (within 10 degrees), 30 cm or more above it and holding as large a share
//      of the points as a table must (`min_plane_fraction`), is the table instead: the dominant
//      plane was the floor, seen past the table's edge;
//   3. the 2-D convex hull of all full-resolution points within `plane_distance` of the plane
//      (Akl-Toussaint filter, then Andrew's monotone chain) bounds the table; coplanar points
//      elsewhere in the scene widen it;
//   4. candidates: full-resolution points between `min_height` and `max_height` above the plane
//      whose projection lies inside the hull (the polygonal prism of PCL's
//      ExtractPolygonalPrismData) or within `hull_margin` of it;
//   5. grouping (`grouping`):
//      kConvexity (default): small surface patches (esf/surface_patches.hpp: image tiles of an
//      organised frame, voxels otherwise) join where the surface between them is convex or
//      nearly flat (esf/convexity_grouping.hpp), so touching, stacked and leaning objects part
//      at the concave creases between them; then, in organised frames, the parts of an object
//      cut apart by an occluder in front of it join (src/segmentation/occluded_parts.hpp), and in
//      any cloud a container's inside joins its outside (src/segmentation/container_parts.hpp);
//      kEuclidean: two candidates belong to one cluster when a chain of candidates links them
//      with steps of at most `cluster_tolerance` (the clusters of PCL's
//      EuclideanClusterExtraction, found on a hash grid instead of a k-d tree);
//   0. an unorganised cloud whose finite points are a depth image's (each within 0.01 pixel of
//      its own pixel centre of `image_camera`, as when the invalid pixels of a frame were
//      dropped) is segmented as that image, so that the organised steps apply; its clusters'
//      indices and points still refer to the input, in its order;
//   6. clusters with fewer than `min_cluster_points` or more than `max_cluster_points`
//      full-resolution points are dropped; in organised frames the others grow down to their
//      rims below `min_height` (`rim_height`), and an open container takes in its floor
//      (`join_container_floors`); they are sorted by point count (descending), then by centroid
//      x, y, z.
//
// Results are identical for every thread count. segment_scene() is re-entrant.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "esf/core/camera.hpp"
#include "esf/core/enum_names.hpp"
#include "esf/core/point_cloud.hpp"
#include "esf/segmentation/convexity_grouping.hpp"
#include "esf/segmentation/surface_patches.hpp"

namespace esf {

/// How the points above the table are grouped into objects.
enum class Grouping {
    /// Surface patches joined where the surface is convex (esf/convexity_grouping.hpp): splits
    /// touching, stacked and leaning objects at the concave creases between them.
    kConvexity,
    /// Euclidean clustering: everything that touches is one object.
    kEuclidean,
};

/// "convexity", "euclidean" (to_string, parse_enum<Grouping>).
template <>
struct EnumNames<Grouping> {
    static constexpr const char* what = "grouping";
    static constexpr std::array<EnumName<Grouping>, 2> table{
        {{Grouping::kConvexity, "convexity"}, {Grouping::kEuclidean, "euclidean"}}};
};

/// Thresholds of segment_scene(). Lengths are in metres (the defaults suit Kinect-like sensors at
/// 0.5 to 2 m; scale them for clouds in other units).
struct SegmentationOptions {
    // Plane fit.
    /// m; max distance of a table point to the plane (RANSAC): the same margin as min_height
    /// (chosen with it, BENCHMARKS.md)
    float plane_distance = 0.0075f;
    int plane_iterations = 500;         ///< max RANSAC hypotheses (fewer when the plane is clear)
    std::size_t plane_samples = 12000;  ///< points the plane is fitted on (subsample), >= 3
    double plane_confidence = 0.999;    ///< RANSAC stops when a better plane is this unlikely
    /// A plane is accepted when it holds at least this many full-resolution points...
    std::size_t min_plane_points = 1000;
    /// ...and at least this fraction of the finite points.
    double min_plane_fraction = 0.1;
    // Objects.
    /// m above the plane where objects start (below: table, noise). 7.5 mm keeps flat things
    /// (scissors, plates, wrenches) that 1 cm lost, above the sensor's noise on the table
    /// (chosen on generated scenes and real fold 0/2, BENCHMARKS.md).
    float min_height = 0.0075f;
    float max_height = 0.40f;  ///< m above the plane where objects end (higher points ignored)
    /// m: points whose projection lies within this of the table's hull stand on the table too.
    /// The hull is the visible table's, which misses what a large object hides behind it (chosen
    /// on generated scenes and real fold 0, BENCHMARKS.md); 0: the hull itself.
    float hull_margin = 0.10f;
    /// Organised frames: a cluster then takes in the pixels next to it (repeatedly, without a
    /// depth step of more than 1 cm) that stand below min_height but above max(rim_height,
    /// rim_noise r^2), r the pixel's distance from the viewpoint in metres: an object's lowest
    /// rim, which min_height cuts off (a lying can's underside), above the sensor's noise on the
    /// table (rim_noise: one disparity step of a Kinect v1, 3.2 mm at 1 m). rim_height >=
    /// min_height: off. Chosen on generated scenes and real fold 0 (BENCHMARKS.md).
    float rim_height = 0.003f;
    float rim_noise = 0.0032f;  ///< m per square metre of range
    /// Sensor position in the cloud's frame: its side of the plane is "above".
    Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();
    // Grouping.
    Grouping grouping = Grouping::kConvexity;
    /// kConvexity: the patches (image tiles for organised clouds, voxels otherwise; their
    /// viewpoint is replaced by `viewpoint`) and the convexity test.
    SurfacePatchOptions patches;
    ConvexityOptions convexity;
    /// kConvexity, organised clouds: planar groups on either side of an occluder in front of
    /// them, lying in one plane, are one object (a box seen on both sides of a can).
    bool join_occluded_parts = true;
    /// kConvexity: a group whose footprint on the plane lies within another group's round
    /// footprint is its inside (a cup's, a bowl's or a pot's inner wall and bottom).
    bool join_container_parts = true;
    /// Organised frames: a cluster whose upper part is round (an open container seen from
    /// above) takes in the points below min_height inside that circle (less 1 cm) that no
    /// cluster holds: its floor, a few millimetres above the table (a bowl's, a cup's, a plate's
    /// inner bottom).
    bool join_container_floors = true;
    /// kEuclidean: clustering.
    float cluster_tolerance = 0.02f;           ///< m; largest gap inside one object
    std::size_t min_cluster_points = 100;      ///< full-resolution points, >= 1
    std::size_t max_cluster_points = 1000000;  ///< full-resolution points
    /// The camera an unorganised cloud may be the depth image of (step 0, above); std::nullopt:
    /// unorganised clouds stay unorganised.
    std::optional<CameraIntrinsics> image_camera = CameraIntrinsics::kinect();
    // Execution.
    std::uint64_t seed = 0;  ///< RANSAC seed
    int threads = 0;         ///< 0 = all cores
};

/// A plane n . p + d = 0 with |n| = 1 and n pointing to the viewpoint's side (n . v + d > 0).
struct Plane {
    Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
    float d = 0.0f;

    /// Signed distance of p above the plane (positive on the viewpoint's side).
    float height(const Eigen::Vector3f& p) const { return normal.dot(p) + d; }
};

enum class ClusterStatus {
    kOk,
    /// The object may be cut off: it touches the border of an organised cloud's image, or
    /// reaches `max_height`. The message says which.
    kMaybeTruncated,
};

/// "ok", "maybe_truncated".
template <>
struct EnumNames<ClusterStatus> {
    static constexpr const char* what = "cluster status";
    static constexpr std::array<EnumName<ClusterStatus>, 2> table{
        {{ClusterStatus::kOk, "ok"}, {ClusterStatus::kMaybeTruncated, "maybe_truncated"}}};
};

/// One object above the table.
struct Cluster {
    Points points;                                       ///< full-resolution points, in input order
    std::vector<std::uint32_t> indices;                  ///< their indices in the input cloud
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  ///< m, mean of `points`
    /// m: x = length, y = width (sides of the smallest rectangle in the plane that holds the
    /// projected points; length >= width), z = height of the highest point above the plane.
    Eigen::Vector3f size = Eigen::Vector3f::Zero();
    /// Unit vector in the plane along the length side (the width side is normal x length_axis).
    Eigen::Vector3f length_axis = Eigen::Vector3f::UnitX();
    ClusterStatus status = ClusterStatus::kOk;
    std::string message;  ///< empty when kOk
};

struct SegmentationResult {
    bool plane_found = false;
    Plane plane;  ///< the best plane found, also when it was rejected (then plane_found = false)
    std::size_t plane_inliers = 0;  ///< full-resolution points within plane_distance of it
    std::size_t finite_points = 0;  ///< finite points in the input
    std::vector<Cluster> clusters;
    /// What happened, for people: "no dominant plane: ...", "no objects above the plane",
    /// "3 objects above the plane".
    std::string message;
};

/// Throws std::invalid_argument when an option is out of range.
void validate(const SegmentationOptions& options);

/// Two clusters of one segmentation as one object: the points and indices of both (a's first),
/// centroid, size and length axis measured again on `plane`; maybe truncated when either is.
/// Throws std::invalid_argument for a cluster without points.
Cluster merge_clusters(const Cluster& a, const Cluster& b, const Plane& plane);

/// Marks a pixel of depth_image_of()'s `source` that no point lies on.
inline constexpr std::uint32_t kNoPoint = 0xffffffffu;

/// The depth image (organised, camera.width x camera.height) whose finite points `points` are:
/// each finite point within 0.01 pixel of its own pixel centre of `camera` (in front of it,
/// inside the image, no two on one pixel), the other pixels NaN; what is left of a depth frame
/// whose invalid pixels were dropped. `source`, when given, gets each pixel's index in `points`
/// (kNoPoint where none). std::nullopt when a finite point breaks the rule or fewer than 3 are
/// finite. Throws std::invalid_argument for a camera that CameraIntrinsics::validate() refuses.
std::optional<PointCloud> depth_image_of(std::span<const Eigen::Vector3f> points,
                                         const CameraIntrinsics& camera,
                                         std::vector<std::uint32_t>* source = nullptr);

/// Segments a cloud; organised clouds (height > 1) also flag clusters touching the image border.
/// Throws std::invalid_argument for an empty cloud, a cloud without finite points, bad options
/// or coordinates too large for the clustering grid. A scene without a plane or without objects
/// is no error: the result says so.
SegmentationResult segment_scene(const PointCloud& cloud, const SegmentationOptions& options = {});

/// The same for an unorganised set of points (non-finite points are skipped).
SegmentationResult segment_scene(std::span<const Eigen::Vector3f> points,
                                 const SegmentationOptions& options = {});

}  // namespace esf
