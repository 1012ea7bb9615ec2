// Google Benchmark of table-scene segmentation on the real 640 x 480 scenes of
// $ESF_DATA/real/scenes (default ../shared/data), on 1 and 2 threads, side by side with the
// classic full-resolution PCL pipeline (SACSegmentation, ConvexHull, ExtractPolygonalPrismData,
// EuclideanClusterExtraction with the same thresholds). Ends with a table of medians and the
// ratio PCL / esf (skipped with ESF_BENCH_SIDE_BY_SIDE=0). A synthetic depth image (plane and five
// boxes) is always measured.

#include <benchmark/benchmark.h>
#include <pcl/ModelCoefficients.h>
#include <pcl/filters/extract_indices.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/extract_polygonal_prism_data.h>
#include <pcl/segmentation/sac_segmentation.h>
#include <pcl/surface/convex_hull.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bench_data.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/io/depth_image.hpp"
#include "esf/segmentation/segmentation.hpp"

namespace {

namespace fs = std::filesystem;

fs::path scene_dir() { return esf::bench::data_dir() / "real/scenes"; }

const std::vector<std::string>& scene_names() {
    static const std::vector<std::string> names = [] {
        std::vector<std::string> found;
        if (fs::is_directory(scene_dir()))
            for (const auto& entry : fs::directory_iterator(scene_dir()))
                if (entry.path().extension() == ".pcd") found.push_back(entry.path().stem());
        std::sort(found.begin(), found.end());
        return found;
    }();
    return names;
}

const esf::PointCloud& scene(const std::string& name) {
    static std::map<std::string, esf::PointCloud> cache;
    auto it = cache.find(name);
    if (it == cache.end())
        it = cache.emplace(name, esf::read_cloud((scene_dir() / (name + ".pcd")).string())).first;
    return it->second;
}

// A 640 x 480 depth image: a table 1 m below a camera pitched down by 0.6 rad, and the top faces
// of five boxes.
esf::PointCloud synthetic_scene() {
    esf::DepthImage image{640, 480, std::vector<std::uint16_t>(640 * 480, 0)};
    const esf::CameraIntrinsics k;
    const double tilt = 0.6;  // camera pitch (rad); the table is y' = 1 m below the camera
    for (std::uint32_t v = 0; v < 480; ++v)
        for (std::uint32_t u = 0; u < 640; ++u) {
            const double x = (u - k.cx) / k.fx, y = (v - k.cy) / k.fy;
            // Ray (x, y, 1) in the camera frame; height below the camera along the world "down".
            const double down = y * std::cos(tilt) + std::sin(tilt);
            if (down <= 0.05) continue;
            double depth = 1.0 / down;
            const double forward = (std::cos(tilt) - y * std::sin(tilt)) * depth;
            const double side = x * depth;
            for (int b = 0; b < 5; ++b) {  // boxes 10 cm wide, 8 to 24 cm tall, 25 cm apart
                const double bx = -0.5 + 0.25 * b, bf = 1.4;
                const double top = 1.0 - (0.08 + 0.04 * b);
                if (std::abs(side - bx) < 0.05 && std::abs(forward - bf) < 0.05)
                    depth = std::min(depth, top / down);  // the box's top face
            }
            // The ray is (x, y, 1) * depth, so depth is z, the value a depth image stores.
            if (depth > 0.3 && depth < 6.0)
                image.depth[v * 640 + u] = static_cast<std::uint16_t>(depth * 1000);
        }
    return esf::depth_to_cloud(image);
}

void BM_SegmentSynthetic(benchmark::State& state) {
    static const esf::PointCloud cloud = synthetic_scene();
    esf::SegmentationOptions options;
    options.threads = static_cast<int>(state.range(0));
    std::size_t clusters = 0;
    for (auto _ : state) {
        const esf::SegmentationResult result = esf::segment_scene(cloud, options);
        clusters = result.clusters.size();
        benchmark::DoNotOptimize(result);
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(cloud.points.size()));
    state.SetLabel(std::to_string(clusters) + " clusters");
}
BENCHMARK(BM_SegmentSynthetic)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void segment_real(benchmark::State& state, const std::string& name, int threads) {
    const esf::PointCloud& cloud = scene(name);
    esf::SegmentationOptions options;
    options.threads = threads;
    std::size_t clusters = 0;
    for (auto _ : state) {
        const esf::SegmentationResult result = esf::segment_scene(cloud, options);
        clusters = result.clusters.size();
        benchmark::DoNotOptimize(result);
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(cloud.points.size()));
    state.SetLabel(std::to_string(clusters) + " clusters");
}

// The textbook PCL tabletop pipeline at full resolution, with esf's default thresholds.
std::size_t pcl_pipeline(const pcl::PointCloud<pcl::PointXYZ>::Ptr& cloud) {
    const esf::SegmentationOptions o;
    pcl::SACSegmentation<pcl::PointXYZ> sac;
    sac.setModelType(pcl::SACMODEL_PLANE);
    sac.setMethodType(pcl::SAC_RANSAC);
    sac.setDistanceThreshold(o.plane_distance);
    sac.setMaxIterations(o.plane_iterations);
    sac.setProbability(o.plane_confidence);
    sac.setInputCloud(cloud);
    pcl::PointIndices::Ptr inliers(new pcl::PointIndices);
    pcl::ModelCoefficients::Ptr coefficients(new pcl::ModelCoefficients);
    sac.segment(*inliers, *coefficients);
    if (inliers->indices.size() < 3) return 0;
    pcl::PointCloud<pcl::PointXYZ>::Ptr table(new pcl::PointCloud<pcl::PointXYZ>);
    pcl::ExtractIndices<pcl::PointXYZ> extract;
    extract.setInputCloud(cloud);
    extract.setIndices(inliers);
    extract.filter(*table);
    pcl::PointCloud<pcl::PointXYZ>::Ptr hull(new pcl::PointCloud<pcl::PointXYZ>);
    pcl::ConvexHull<pcl::PointXYZ> chull;
    chull.setInputCloud(table);
    chull.setDimension(2);
    chull.reconstruct(*hull);
    pcl::ExtractPolygonalPrismData<pcl::PointXYZ> prism;
    prism.setInputCloud(cloud);
    prism.setInputPlanarHull(hull);
    prism.setHeightLimits(o.min_height, o.max_height);
    pcl::PointIndices::Ptr objects(new pcl::PointIndices);
    prism.segment(*objects);
    pcl::EuclideanClusterExtraction<pcl::PointXYZ> clustering;
    pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
    clustering.setSearchMethod(tree);
    clustering.setInputCloud(cloud);
    clustering.setIndices(objects);
    clustering.setClusterTolerance(o.cluster_tolerance);
    clustering.setMinClusterSize(static_cast<int>(o.min_cluster_points));
    clustering.setMaxClusterSize(static_cast<int>(o.max_cluster_points));
    std::vector<pcl::PointIndices> clusters;
    clustering.extract(clusters);
    return clusters.size();
}

pcl::PointCloud<pcl::PointXYZ>::Ptr finite_pcl_cloud(const esf::PointCloud& cloud) {
    pcl::PointCloud<pcl::PointXYZ>::Ptr out(new pcl::PointCloud<pcl::PointXYZ>);
    for (const auto& p : cloud.points)
        if (p.allFinite()) out->push_back({p.x(), p.y(), p.z()});
    return out;
}

void pcl_real(benchmark::State& state, const std::string& name) {
    const auto cloud = finite_pcl_cloud(scene(name));
    std::size_t clusters = 0;
    for (auto _ : state) clusters = pcl_pipeline(cloud);
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(cloud->size()));
    state.SetLabel(std::to_string(clusters) + " clusters");
}

template <typename F>
double median_ms(F&& f, int runs) {
    std::vector<double> times;
    for (int r = 0; r < runs; ++r) {
        const auto start = std::chrono::steady_clock::now();
        f();
        times.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count());
    }
    std::sort(times.begin(), times.end());
    return times[times.size() / 2];
}

void print_side_by_side() {
    if (scene_names().empty()) return;
    std::printf("\n%-40s %10s %10s %10s %8s\n", "scene (median of 9 runs)", "esf 1 thr",
                "esf 2 thr", "PCL", "ratio");
    double sum_ratio = 0.0;
    for (const std::string& name : scene_names()) {
        const esf::PointCloud& cloud = scene(name);
        esf::SegmentationOptions one, two;
        one.threads = 1;
        two.threads = 2;
        const double t1 = median_ms([&] { esf::segment_scene(cloud, one); }, 9);
        const double t2 = median_ms([&] { esf::segment_scene(cloud, two); }, 9);
        const auto pcl_cloud = finite_pcl_cloud(cloud);
        const double tp = median_ms([&] { pcl_pipeline(pcl_cloud); }, 3);
        std::printf("%-40s %8.2fms %8.2fms %8.1fms %7.1fx\n", name.c_str(), t1, t2, tp, tp / t2);
        sum_ratio += tp / t2;
    }
    std::printf("ratio: %.1f (PCL full-resolution pipeline / esf on 2 threads, mean)\n",
                sum_ratio / static_cast<double>(scene_names().size()));
}

}  // namespace

int main(int argc, char** argv) {
    for (const std::string& name : scene_names()) {
        for (int threads : {1, 2})
            benchmark::RegisterBenchmark(
                ("BM_SegmentReal/" + name + "/threads:" + std::to_string(threads)).c_str(),
                [name, threads](benchmark::State& s) { segment_real(s, name, threads); })
                ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("BM_PclPipelineReal/" + name).c_str(),
                                     [name](benchmark::State& s) { pcl_real(s, name); })
            ->Unit(benchmark::kMillisecond)
            ->Iterations(3);
    }
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    if (scene_names().empty())
        std::printf("shared data missing: %s (set ESF_DATA)\n", scene_dir().c_str());
    else if (const char* side = std::getenv("ESF_BENCH_SIDE_BY_SIDE"); !side || *side != '0')
        print_side_by_side();
    return 0;
}
