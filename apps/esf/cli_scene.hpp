#pragma once
// Options shared by the subcommands that read table scenes (esf segment, esf scene): the depth
// PNG intrinsics and the segmentation thresholds, defined once so that both commands spell and
// document them alike.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "esf/core/point_cloud.hpp"
#include "esf/io/depth_image.hpp"
#include "esf/segmentation/segmentation.hpp"

namespace esf::cli {

struct SceneInputArgs {
    bool depth_png = false;
    CameraIntrinsics intrinsics;  ///< of depth PNGs, and of clouds that are a depth image's points
    bool keep_unorganised = false;
    double depth_scale = 0.001;
    SegmentationOptions segmentation;
    std::vector<float> viewpoint = {0.0f, 0.0f, 0.0f};
};

/// --depth-png, --fx, --fy, --cx, --cy, --depth-scale. `args` must outlive `cmd`.
void add_depth_png_options(CLI::App& cmd, SceneInputArgs& args);

/// --plane-distance ... --max-cluster-points, --viewpoint and --seed (the segmentation's
/// thresholds; each command adds its own --threads). `args` must outlive `cmd`.
void add_segmentation_options(CLI::App& cmd, SceneInputArgs& args);

/// The segmentation options with the viewpoint applied; throws std::invalid_argument when one
/// is out of range.
SegmentationOptions segmentation_options(const SceneInputArgs& args);

/// Reads a scene: a point cloud (.pcd, .ply, .xyz), or a 16-bit depth PNG (--depth-png or the
/// .png extension) back-projected with the intrinsics.
PointCloud load_scene_cloud(const std::string& path, const SceneInputArgs& args);

}  // namespace esf::cli
