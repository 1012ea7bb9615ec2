// Where convexity grouping joins two objects (a study; BENCHMARKS.md, "Colour across packed
// boxes"): the surface patches of each labelled scene's object pixels (the grouping's own patches,
// default options), grouped by convexity as segmentation groups them, and every pair of adjacent
// patches with the object each patch mostly holds and whether both ended in one segment.
// bench/patch_colour_study.py reads the files with the scene's colours.
//   patch_study OUT_DIR SCENE.pcd...
// writes OUT_DIR/NAME.points.csv (point, patch: the scene file's point index) and
// OUT_DIR/NAME.edges.csv (a, b, joined, object_a, object_b) for each scene NAME.pcd.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "esf/evaluation/segmentation_evaluation.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/segmentation/convexity_grouping.hpp"
#include "esf/segmentation/segmentation.hpp"
#include "esf/segmentation/surface_patches.hpp"

namespace fs = std::filesystem;

namespace {

void study(const fs::path& scene_file, const fs::path& out_dir) {
    const esf::PointCloud cloud = esf::read_cloud(scene_file.string());
    if (cloud.labels.size() != cloud.points.size())
        throw std::runtime_error(scene_file.string() + ": no per-point labels");
    // The frame as segmentation sees it: organised, or the depth image of a frame saved without
    // its invalid pixels.
    std::vector<std::uint32_t> source;
    std::optional<esf::PointCloud> image;
    if (cloud.height <= 1) {
        image = esf::depth_image_of(cloud.points, esf::CameraIntrinsics::kinect(), &source);
        if (!image) throw std::runtime_error(scene_file.string() + ": not a depth image's points");
    }
    const esf::PointCloud& frame = image ? *image : cloud;
    const esf::LabelScheme scheme;
    std::vector<std::uint32_t> members, object;
    for (std::uint32_t p = 0; p < frame.points.size(); ++p) {
        const std::uint32_t s = image ? source[p] : p;
        if (s == esf::kNoPoint || !frame.points[p].allFinite()) continue;
        const std::uint32_t id = cloud.labels[s] / scheme.divisor;
        if (id < scheme.first_object) continue;
        members.push_back(p);
        object.push_back(id);
    }
    const esf::PatchGraph graph =
        esf::image_patches(frame.points, frame.width, frame.height, members, {});
    const std::vector<std::uint32_t> segment = esf::convex_segments(graph, {});
    std::vector<std::map<std::uint32_t, std::uint32_t>> votes(graph.patches.size());
    const std::string name = scene_file.stem().string();
    std::ofstream points(out_dir / (name + ".points.csv"));
    points << "point,patch\n";
    for (std::size_t k = 0; k < members.size(); ++k) {
        ++votes[graph.patch_of[k]][object[k]];
        points << (image ? source[members[k]] : members[k]) << ',' << graph.patch_of[k] << '\n';
    }
    std::vector<std::uint32_t> main_object(graph.patches.size(), 0);
    for (std::size_t p = 0; p < votes.size(); ++p) {
        std::uint32_t best = 0;
        for (const auto& [id, count] : votes[p])
            if (count > best) {
                best = count;
                main_object[p] = id;
            }
    }
    std::ofstream edges(out_dir / (name + ".edges.csv"));
    edges << "a,b,joined,object_a,object_b\n";
    for (const esf::PatchEdge& e : graph.edges)
        edges << e.a << ',' << e.b << ',' << (segment[e.a] == segment[e.b] ? 1 : 0) << ','
              << main_object[e.a] << ',' << main_object[e.b] << '\n';
    if (!points || !edges) throw std::runtime_error("cannot write into " + out_dir.string());
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: patch_study OUT_DIR SCENE.pcd...\n");
        return 1;
    }
    try {
        fs::create_directories(argv[1]);
        for (int i = 2; i < argc; ++i) study(argv[i], argv[1]);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "patch_study: error: %s\n", e.what());
        return 2;
    }
    return 0;
}
