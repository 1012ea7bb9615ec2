// esf segment SCENE -o DIR : table-scene segmentation into object clusters.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "cli_scene.hpp"
#include "commands.hpp"
#include "core/atomic_file.hpp"
#include "core/elapsed_time.hpp"
#include "esf/core/error.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/io/depth_image.hpp"
#include "esf/segmentation/segmentation.hpp"

namespace esf::cli {

namespace {

namespace fs = std::filesystem;

struct SegmentArgs {
    std::string scene;
    std::string output;
    SceneInputArgs input;  // depth PNG intrinsics and segmentation options (cli_scene.hpp)
    int threads = 0;
    bool json = false;
};

nlohmann::json vec(const Eigen::Vector3f& v) { return {v.x(), v.y(), v.z()}; }

std::string cluster_file(std::size_t index) {
    char name[48];
    std::snprintf(name, sizeof name, "cluster_%03zu.pcd", index);
    return name;
}

void run_segment(const SegmentArgs& args) {
    SegmentationOptions options = segmentation_options(args.input);
    options.threads = args.threads;
    const PointCloud cloud = load_scene_cloud(args.scene, args.input);

    const auto start = std::chrono::steady_clock::now();
    const SegmentationResult result = segment_scene(cloud, options);
    const double ms = detail::milliseconds_since(start);

    // Output folder: created when missing; clusters of an earlier run are removed first so that
    // the folder always matches summary.json.
    const fs::path dir(args.output);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir))
        throw IoError(file_message(args.output, 0, "cannot create the output folder"));
    static const std::regex kClusterName(R"(cluster_\d{3,}\.pcd)");
    for (const auto& entry : fs::directory_iterator(dir))
        if (entry.is_regular_file() &&
            std::regex_match(entry.path().filename().string(), kClusterName))
            fs::remove(entry.path());

    nlohmann::json summary;
    summary["input"] = args.scene;
    summary["points"] = cloud.points.size();
    summary["finite_points"] = result.finite_points;
    summary["width"] = cloud.width;
    summary["height"] = cloud.height;
    summary["plane_found"] = result.plane_found;
    summary["plane"] = {{"normal", vec(result.plane.normal)},
                        {"d", result.plane.d},
                        {"inliers", result.plane_inliers}};
    summary["message"] = result.message;
    const SegmentationOptions& o = options;
    summary["options"] = {{"plane_distance_m", o.plane_distance},
                          {"plane_iterations", o.plane_iterations},
                          {"plane_samples", o.plane_samples},
                          {"min_plane_points", o.min_plane_points},
                          {"min_plane_fraction", o.min_plane_fraction},
                          {"min_height_m", o.min_height},
                          {"max_height_m", o.max_height},
                          {"viewpoint_m", vec(o.viewpoint)},
                          {"grouping", to_string(o.grouping)},
                          {"concavity_tolerance_deg", o.convexity.concavity_tolerance_deg},
                          {"patch_pixels", o.patches.tile_pixels},
                          {"patch_size_m", o.patches.voxel_size},
                          {"cluster_tolerance_m", o.cluster_tolerance},
                          {"min_cluster_points", o.min_cluster_points},
                          {"max_cluster_points", o.max_cluster_points},
                          {"seed", o.seed}};
    summary["clusters"] = nlohmann::json::array();
    for (std::size_t k = 0; k < result.clusters.size(); ++k) {
        const Cluster& c = result.clusters[k];
        PointCloud out;
        out.points = c.points;
        out.width = static_cast<std::uint32_t>(c.points.size());
        out.height = 1;
        write_pcd((dir / cluster_file(k)).string(), out);
        summary["clusters"].push_back(
            {{"file", cluster_file(k)},
             {"points", c.points.size()},
             {"centroid_m", vec(c.centroid)},
             {"size_m", {{"length", c.size.x()}, {"width", c.size.y()}, {"height", c.size.z()}}},
             {"length_axis", vec(c.length_axis)},
             {"status", to_string(c.status)},
             {"message", c.message}});
    }
    const fs::path summary_path = dir / "summary.json";
    detail::write_file_atomically(summary_path, summary.dump(2) + '\n');

    if (args.json) {
        std::cout << summary.dump(2) << '\n';
        return;
    }
    const Plane& p = result.plane;
    if (result.plane_inliers > 0)
        std::printf("plane%s: normal (%.3f, %.3f, %.3f), d = %.3f m, %zu of %zu points\n",
                    result.plane_found ? "" : " (rejected)", p.normal.x() + 0.0f,
                    p.normal.y() + 0.0f, p.normal.z() + 0.0f, p.d, result.plane_inliers,
                    result.finite_points);
    if (!result.clusters.empty()) {
        std::printf("%-16s %8s  %-24s %-22s %s\n", "file", "points", "centroid x y z (m)",
                    "length width height (m)", "status");
        for (std::size_t k = 0; k < result.clusters.size(); ++k) {
            const Cluster& c = result.clusters[k];
            std::printf("%-16s %8zu  %7.3f %7.3f %7.3f  %6.3f %6.3f %6.3f   %s\n",
                        cluster_file(k).c_str(), c.points.size(), c.centroid.x(), c.centroid.y(),
                        c.centroid.z(), c.size.x(), c.size.y(), c.size.z(),
                        c.status == ClusterStatus::kOk ? "ok" : c.message.c_str());
        }
    }
    std::printf("%s (%.1f ms); wrote %s\n", result.message.c_str(), ms,
                summary_path.string().c_str());
}

}  // namespace

void add_segment_command(CLI::App& app) {
    auto args = std::make_shared<SegmentArgs>();
    CLI::App* cmd = add_command(
        app, "segment", "Split a table scene into the objects standing on the table",
        "The dominant plane is found (RANSAC); the points standing on it (above it on the\n"
        "sensor's side, inside its convex hull) are grouped into objects. By default\n"
        "(--grouping convexity) small surface patches join where the surface between them is\n"
        "convex or nearly flat, so touching, stacked and leaning objects part at the concave\n"
        "creases between them; the parts of an object cut apart by an occluder in front of it\n"
        "join again (organised clouds), and a container's inside joins its outside.\n"
        "--grouping euclidean makes all points that touch (gaps up to --cluster-tolerance) one\n"
        "object. Objects with too few or too many points are dropped. Writes\n"
        "DIR/cluster_000.pcd ... (full-resolution points, largest cluster first; older\n"
        "cluster_NNN.pcd files in DIR are removed) and DIR/summary.json (plane, clusters with\n"
        "centroid, size and point count), and prints a\n"
        "table. A scene without a plane or without objects is reported, not an error.");
    cmd->add_option("scene", args->scene,
                    "Point cloud (.pcd, .ply, .xyz), organised or not, or a 16-bit depth PNG")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("-o,--output", args->output, "Output folder (created when missing)")
        ->required();
    add_depth_png_options(*cmd, args->input);
    add_segmentation_options(*cmd, args->input);
    add_threads_option(*cmd, args->threads);
    cmd->add_flag("--json", args->json, "Print summary.json to stdout instead of the table");
    cmd->callback([args] { run_segment(*args); });
}

}  // namespace esf::cli
