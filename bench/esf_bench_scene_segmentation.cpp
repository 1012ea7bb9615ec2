// Segmentation quality and time on labelled organised scenes, per scene type: objects found as
// one cluster (esf/segmentation_evaluation.hpp), split, merged, missed, and milliseconds per
// frame (best of 3), for convexity grouping, Euclidean clustering and PCL's LCCP (supervoxels +
// local convexity, Stein et al. 2014, PCL's example settings) side by side. LCCP runs on the
// same points above the table as ours (the union of Euclidean clusters of one point or more);
// its time is LCCP alone, without the plane fit.
//
//   esf_bench_scene_segmentation [SCENE_DIR]     (default: $ESF_DATA/real/scenes)
//
// Scene types follow the mOSD learn split's numbering (0-16 boxes, 17-24 stacked boxes, 25-32
// occluded objects, 33-44 cylindric objects); other file names count as "other".

#include <pcl/point_types.h>
#include <pcl/segmentation/lccp_segmentation.h>
#include <pcl/segmentation/supervoxel_clustering.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include "bench_data.hpp"
#include "esf/evaluation/segmentation_evaluation.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/segmentation/segmentation.hpp"
#include "io/png_writer.hpp"

namespace {

namespace fs = std::filesystem;

std::string scene_type(const std::string& name) {
    static const std::regex kMosd(R"(mosd_learn(\d+)\.pcd)");
    std::smatch m;
    if (!std::regex_match(name, m, kMosd)) return "other";
    const int n = std::stoi(m[1]);
    if (n <= 16) return "isolated boxes";
    if (n <= 24) return "stacked boxes";
    if (n <= 32) return "occluded";
    return "cylindric";
}

struct Tally {
    std::size_t objects = 0, found = 0, split = 0, merged = 0, missed = 0, frames = 0;
    double ms = 0.0;
    void add(const esf::SegmentationScore& s, double frame_ms) {
        objects += s.objects.size();
        found += s.count(esf::SegmentOutcome::kFound);
        split += s.count(esf::SegmentOutcome::kSplit);
        merged += s.count(esf::SegmentOutcome::kMerged);
        missed += s.count(esf::SegmentOutcome::kMissed);
        ++frames;
        ms += frame_ms;
    }
};

/// PCL's LCCP on the given points of `cloud` (indices): clusters of at least `min_points`.
std::vector<esf::Cluster> lccp_clusters(const esf::PointCloud& cloud,
                                        const std::vector<std::uint32_t>& indices,
                                        std::size_t min_points) {
    using PointT = pcl::PointXYZRGBA;
    pcl::PointCloud<PointT>::Ptr input(new pcl::PointCloud<PointT>);
    for (const std::uint32_t i : indices) {
        PointT p;
        p.x = cloud.points[i].x();
        p.y = cloud.points[i].y();
        p.z = cloud.points[i].z();
        p.rgba = 0;
        input->push_back(p);
    }
    const float voxel_resolution = 0.0075f, seed_resolution = 0.03f;
    pcl::SupervoxelClustering<PointT> super(voxel_resolution, seed_resolution);
    super.setUseSingleCameraTransform(false);
    super.setInputCloud(input);
    super.setColorImportance(0.0f);
    super.setSpatialImportance(1.0f);
    super.setNormalImportance(4.0f);
    std::map<std::uint32_t, pcl::Supervoxel<PointT>::Ptr> supervoxels;
    super.extract(supervoxels);
    std::multimap<std::uint32_t, std::uint32_t> adjacency;
    super.getSupervoxelAdjacency(adjacency);
    pcl::LCCPSegmentation<PointT> lccp;
    lccp.setConcavityToleranceThreshold(10.0f);
    lccp.setSanityCheck(true);
    lccp.setSmoothnessCheck(true, voxel_resolution, seed_resolution, 0.1f);
    lccp.setKFactor(0);
    lccp.setInputSupervoxels(supervoxels, adjacency);
    lccp.setMinSegmentSize(3);
    lccp.segment();
    pcl::PointCloud<pcl::PointXYZL>::Ptr labelled = super.getLabeledCloud();
    lccp.relabelCloud(*labelled);
    std::map<std::uint32_t, esf::Cluster> by_label;
    for (std::size_t k = 0; k < labelled->size() && k < indices.size(); ++k) {
        const std::uint32_t label = (*labelled)[k].label;
        if (label == 0) continue;
        by_label[label].indices.push_back(indices[k]);
    }
    std::vector<esf::Cluster> clusters;
    for (auto& [label, c] : by_label)
        if (c.indices.size() >= min_points) clusters.push_back(std::move(c));
    return clusters;
}

}  // namespace

int main(int argc, char** argv) {
    const fs::path dir = argc > 1 ? fs::path(argv[1]) : esf::bench::data_dir() / "real/scenes";
    if (!fs::is_directory(dir)) {
        std::fprintf(stderr, "no scene folder at %s (set ESF_DATA or pass a folder)\n",
                     dir.c_str());
        return 2;
    }
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().extension() == ".pcd") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    const bool verbose = std::getenv("ESF_BENCH_VERBOSE") != nullptr;

    const std::vector<std::pair<std::string, esf::Grouping>> methods = {
        {"convexity", esf::Grouping::kConvexity}, {"euclidean", esf::Grouping::kEuclidean}};
    std::map<std::string, std::map<std::string, Tally>> tallies;  // method -> type -> tally
    for (const fs::path& file : files) {
        const esf::PointCloud cloud = esf::read_cloud(file.string());
        if (cloud.labels.empty()) continue;
        const std::string type = scene_type(file.filename().string());
        {
            esf::SegmentationOptions all;
            all.grouping = esf::Grouping::kEuclidean;
            all.min_cluster_points = 1;
            all.threads = 1;
            std::vector<std::uint32_t> above;
            for (const esf::Cluster& c : esf::segment_scene(cloud, all).clusters)
                above.insert(above.end(), c.indices.begin(), c.indices.end());
            std::sort(above.begin(), above.end());
            const auto start = std::chrono::steady_clock::now();
            const std::vector<esf::Cluster> clusters =
                lccp_clusters(cloud, above, esf::SegmentationOptions{}.min_cluster_points);
            const double ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                    .count();
            const esf::SegmentationScore score =
                esf::score_segmentation(cloud.points, cloud.labels, clusters);
            tallies["pcl-lccp"][type].add(score, ms);
            tallies["pcl-lccp"]["all"].add(score, ms);
        }
        for (const auto& [name, grouping] : methods) {
            esf::SegmentationOptions options;
            options.grouping = grouping;
            options.threads = 1;
            esf::SegmentationResult result;
            double best = 1e30;
            for (int run = 0; run < 3; ++run) {
                const auto start = std::chrono::steady_clock::now();
                result = esf::segment_scene(cloud, options);
                best = std::min(best, std::chrono::duration<double, std::milli>(
                                          std::chrono::steady_clock::now() - start)
                                          .count());
            }
            const esf::SegmentationScore score =
                esf::score_segmentation(cloud.points, cloud.labels, result.clusters);
            tallies[name][type].add(score, best);
            tallies[name]["all"].add(score, best);
            if (const char* dump = std::getenv("ESF_BENCH_DUMP"); dump && cloud.organised()) {
                std::vector<std::uint8_t> rgb(cloud.points.size() * 3, 0);
                for (std::size_t c = 0; c < result.clusters.size(); ++c)
                    for (const std::uint32_t i : result.clusters[c].indices) {
                        const std::uint64_t h = (c + 1) * 0x9E3779B97F4A7C15ull;
                        rgb[3 * i] = static_cast<std::uint8_t>(64 + (h >> 56) % 192);
                        rgb[3 * i + 1] = static_cast<std::uint8_t>(64 + (h >> 48) % 192);
                        rgb[3 * i + 2] = static_cast<std::uint8_t>(64 + (h >> 40) % 192);
                    }
                const std::vector<std::uint8_t> png =
                    esf::detail::encode_png(rgb, cloud.width, cloud.height, 3, 8);
                const fs::path out = fs::path(dump) / (file.stem().string() + "_" + name + ".png");
                std::FILE* f = std::fopen(out.c_str(), "wb");
                if (f) {
                    std::fwrite(png.data(), 1, png.size(), f);
                    std::fclose(f);
                }
            }
            if (verbose) {
                std::printf("%-22s %-10s clusters %2zu:", file.filename().c_str(), name.c_str(),
                            result.clusters.size());
                for (const auto& o : score.objects)
                    std::printf(" o%u=%s(%.2f/%.2f)", o.object_id, esf::to_string(o.outcome),
                                o.coverage, o.purity);
                std::printf("\n");
            }
        }
    }
    for (const auto& [name, types] : tallies) {
        std::printf("\n%s\n%-16s %7s %6s %6s %6s %6s %8s %9s\n", name.c_str(), "scene type",
                    "objects", "found", "split", "merged", "missed", "found %", "ms/frame");
        for (const auto& [type, t] : types)
            std::printf("%-16s %7zu %6zu %6zu %6zu %6zu %7.1f%% %9.2f\n", type.c_str(), t.objects,
                        t.found, t.split, t.merged, t.missed,
                        100.0 * static_cast<double>(t.found) / static_cast<double>(t.objects),
                        t.ms / static_cast<double>(t.frames));
    }
    return 0;
}
