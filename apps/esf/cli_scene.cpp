#include "cli_scene.hpp"

#include <cstdint>
#include <filesystem>
#include <limits>

#include "cli_common.hpp"
#include "esf/io/cloud_io.hpp"

namespace esf::cli {

void add_depth_png_options(CLI::App& cmd, SceneInputArgs& args) {
    cmd.add_flag("--depth-png", args.depth_png,
                 "Read scenes as 16-bit depth PNGs (implied by the .png extension)");
    cmd.add_option("--fx", args.intrinsics.fx,
                   "Depth PNG, or a cloud that is a depth image's points: focal length x (pixels)")
        ->capture_default_str();
    cmd.add_option("--fy", args.intrinsics.fy,
                   "Depth PNG, or a cloud that is a depth image's points: focal length y (pixels)")
        ->capture_default_str();
    cmd.add_option(
           "--cx", args.intrinsics.cx,
           "Depth PNG, or a cloud that is a depth image's points: principal point x (pixels)")
        ->capture_default_str();
    cmd.add_option(
           "--cy", args.intrinsics.cy,
           "Depth PNG, or a cloud that is a depth image's points: principal point y (pixels)")
        ->capture_default_str();
    cmd.add_option("--depth-scale", args.depth_scale,
                   "Depth PNG: metres per unit (0.001 = millimetres; 0.0002 for 5000 per metre)")
        ->capture_default_str();
}

void add_segmentation_options(CLI::App& cmd, SceneInputArgs& args) {
    SegmentationOptions& o = args.segmentation;
    cmd.add_option("--plane-distance", o.plane_distance,
                   "Max distance of a table point to the plane (m)")
        ->capture_default_str();
    cmd.add_option("--plane-iterations", o.plane_iterations,
                   "Max RANSAC hypotheses (fewer when the plane is clear)")
        ->capture_default_str();
    cmd.add_option("--plane-samples", o.plane_samples,
                   "Points the plane is fitted on (an even subsample)")
        ->capture_default_str();
    cmd.add_option("--min-plane-points", o.min_plane_points,
                   "A plane needs at least this many points...")
        ->capture_default_str();
    cmd.add_option("--min-plane-fraction", o.min_plane_fraction,
                   "...and at least this fraction of the finite points (0..1)")
        ->capture_default_str();
    cmd.add_option("--min-height", o.min_height, "Objects start this high above the plane (m)")
        ->capture_default_str();
    cmd.add_option("--max-height", o.max_height, "Objects end this high above the plane (m)")
        ->capture_default_str();
    cmd.add_option("--hull-margin", o.hull_margin,
                   "Points within this of the visible table's hull stand on the table too (m; "
                   "the hull misses what a large object hides behind it)")
        ->capture_default_str();
    cmd.add_option("--rim-height", o.rim_height,
                   "Organised frames: objects grow down to their rims below --min-height, above "
                   "this and one Kinect disparity step (3.2 mm at 1 m) over the plane (m; "
                   "--min-height or more: off)")
        ->capture_default_str();
    cmd.add_option("--viewpoint", args.viewpoint,
                   "Sensor position x y z in the cloud's frame (m); its side of the plane is up")
        ->expected(3)
        ->capture_default_str();
    add_enum_option(cmd, "--grouping", o.grouping,
                    "How points above the table become objects: convexity (surface patches "
                    "joined where the surface is convex; splits touching, stacked and leaning "
                    "objects at the creases between them) or euclidean (all that touches is "
                    "one)");
    cmd.add_option("--concavity-tolerance", o.convexity.concavity_tolerance_deg,
                   "Convexity grouping: neighbouring patches whose normals differ by less than "
                   "this join even where the surface is concave (degrees)")
        ->capture_default_str();
    cmd.add_option("--patch-pixels", o.patches.tile_pixels,
                   "Convexity grouping of organised clouds: side of a surface patch (pixels)")
        ->capture_default_str();
    cmd.add_option("--patch-size", o.patches.voxel_size,
                   "Convexity grouping of unorganised clouds: side of a surface patch (m)")
        ->capture_default_str();
    cmd.add_option("--cluster-tolerance", o.cluster_tolerance,
                   "Euclidean grouping: largest gap between two points of one object (m)")
        ->capture_default_str();
    cmd.add_option("--min-cluster-points", o.min_cluster_points,
                   "Smaller clusters are dropped (points)")
        ->check(
            CLI::Range(std::uint64_t{0}, std::uint64_t{std::numeric_limits<std::uint32_t>::max()}))
        ->capture_default_str();
    cmd.add_option("--max-cluster-points", o.max_cluster_points,
                   "Larger clusters are dropped (points)")
        ->check(
            CLI::Range(std::uint64_t{0}, std::uint64_t{std::numeric_limits<std::uint32_t>::max()}))
        ->capture_default_str();
    cmd.add_flag("--keep-unorganised", args.keep_unorganised,
                 "Segment an unorganised cloud as it is, also when its points are a depth "
                 "image's (each on its own pixel of --fx --fy --cx --cy, 640 x 480: by default "
                 "it is then segmented as that image)");
    add_seed_option(cmd, o.seed, "RANSAC seed");
}

SegmentationOptions segmentation_options(const SceneInputArgs& args) {
    SegmentationOptions options = args.segmentation;
    options.viewpoint = {args.viewpoint[0], args.viewpoint[1], args.viewpoint[2]};
    if (args.keep_unorganised)
        options.image_camera.reset();
    else
        options.image_camera = args.intrinsics;
    validate(options);
    return options;
}

PointCloud load_scene_cloud(const std::string& path, const SceneInputArgs& args) {
    const bool png = args.depth_png || std::filesystem::path(path).extension() == ".png";
    if (!png) return read_cloud(path);
    return depth_to_cloud(read_depth_png(path), args.intrinsics, args.depth_scale);
}

}  // namespace esf::cli
