// Rendering throughput (render only, no descriptor): views/s of real meshes from the shared data
// at the default settings (Kinect camera 640x480, model spanning half the image, Kinect noise),
// the BVH build per mesh, PCL's 150x150 camera, and whole-scene depth frames.
//
//   build/bench/render_bench [--benchmark_filter=...]
//   ESF_DATA=/path/to/shared/data overrides where the meshes are looked for.

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bench_data.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/render/render.hpp"
#include "esf/render/view_sphere.hpp"

namespace {

namespace fs = std::filesystem;

using esf::bench::data_dir;

/// Dense YCB scans (16k triangles, metres) and light KIT models (800 triangles, rescaled).
struct Sample {
    const char* name;
    const char* file;
    bool metric;
};
const std::vector<Sample> kSamples = {
    {"ycb_apple", "meshes/apple/ycb_013_apple.ply", true},
    {"ycb_mug", "meshes/mug/ycb_025_mug.ply", true},
    {"ycb_drill", "meshes/drill/ycb_035_power_drill.ply", true},
    {"kit_bottle", "meshes/bottle/kit_CokePlasticLarge.obj", false},
    {"kit_box", "meshes/box/kit_FruitTea.obj", false},
};

const esf::Mesh* mesh_of(const Sample& sample) {
    static std::map<std::string, esf::Mesh> cache;
    const auto it = cache.find(sample.file);
    if (it != cache.end()) return &it->second;
    const fs::path path = data_dir() / sample.file;
    if (!fs::exists(path)) return nullptr;
    return &cache.emplace(sample.file, esf::load_mesh(path.string())).first->second;
}

esf::RenderOptions options_for(const Sample& sample) {
    esf::RenderOptions options;
    if (!sample.metric) options.target_extent = 0.2;  // a typical real size for KIT objects
    return options;
}

/// All 80 views of one mesh through render_views (BVH build included), range(1) threads.
void BM_RenderViews(benchmark::State& state, const Sample& sample, esf::SensorNoise noise) {
    const esf::Mesh* mesh = mesh_of(sample);
    if (mesh == nullptr) {
        state.SkipWithError("shared mesh missing (set ESF_DATA)");
        return;
    }
    esf::RenderOptions options = options_for(sample);
    options.noise = noise;
    options.threads = static_cast<int>(state.range(0));
    std::size_t points = 0;
    for (auto _ : state) {
        const auto views = esf::render_views(*mesh, options);
        for (const auto& v : views) points += v.points.size();
        benchmark::DoNotOptimize(views.data());
    }
    state.SetItemsProcessed(state.iterations() * 80);
    state.counters["points_per_view"] =
        static_cast<double>(points) / static_cast<double>(state.iterations() * 80);
}

/// One view at a time on one thread, the BVH built once outside the loop.
void BM_RenderOneView(benchmark::State& state, const Sample& sample, bool pcl_camera) {
    const esf::Mesh* mesh = mesh_of(sample);
    if (mesh == nullptr) {
        state.SkipWithError("shared mesh missing (set ESF_DATA)");
        return;
    }
    esf::RenderOptions options = options_for(sample);
    if (pcl_camera) options.camera = esf::CameraIntrinsics::pcl_renderer();
    const esf::MeshRenderer renderer(*mesh, options);
    std::size_t i = 0;
    for (auto _ : state) {
        const esf::RenderedView view = renderer.render_view(i++ % renderer.view_count());
        benchmark::DoNotOptimize(view.points.data());
    }
    state.SetItemsProcessed(state.iterations());
}

/// Embree scene build for one mesh (done once per mesh, shared by its views).
void BM_BuildRenderer(benchmark::State& state, const Sample& sample) {
    const esf::Mesh* mesh = mesh_of(sample);
    if (mesh == nullptr) {
        state.SkipWithError("shared mesh missing (set ESF_DATA)");
        return;
    }
    const esf::RenderOptions options = options_for(sample);
    for (auto _ : state) {
        const esf::MeshRenderer renderer(*mesh, options);
        benchmark::DoNotOptimize(&renderer);
    }
    state.SetItemsProcessed(state.iterations());
}

/// A 640x480 frame of three meshes on an infinite table, Kinect noise, range(0) threads.
void BM_RenderScene(benchmark::State& state) {
    const esf::Mesh* apple = mesh_of(kSamples[0]);
    const esf::Mesh* mug = mesh_of(kSamples[1]);
    const esf::Mesh* drill = mesh_of(kSamples[2]);
    if (!apple || !mug || !drill) {
        state.SkipWithError("shared mesh missing (set ESF_DATA)");
        return;
    }
    std::vector<esf::SceneObject> objects;
    double y = -0.15;
    for (const esf::Mesh* m : {apple, mug, drill}) {
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        pose.translation() = Eigen::Vector3d(0, y, -m->min_corner().z());
        objects.push_back({m, pose});
        y += 0.15;
    }
    esf::SceneOptions options;
    options.table_plane = true;
    options.noise = esf::SensorNoise::kKinect;
    options.threads = static_cast<int>(state.range(0));
    const Eigen::Isometry3d camera = esf::look_at({0.8, 0.0, 0.6}, {0, 0, 0.05});
    for (auto _ : state) {
        const esf::PointCloud cloud = esf::render_scene(objects, camera, options);
        benchmark::DoNotOptimize(cloud.points.data());
    }
    state.SetItemsProcessed(state.iterations());
}

void register_all() {
    for (const Sample& s : kSamples) {
        const std::string name = s.name;
        benchmark::RegisterBenchmark(("BM_RenderViews/" + name + "/kinect").c_str(), BM_RenderViews,
                                     s, esf::SensorNoise::kKinect)
            ->Arg(1)
            ->Arg(2)
            ->ArgName("threads")
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
        benchmark::RegisterBenchmark(("BM_RenderViews/" + name + "/none").c_str(), BM_RenderViews,
                                     s, esf::SensorNoise::kNone)
            ->Arg(1)
            ->ArgName("threads")
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
        benchmark::RegisterBenchmark(("BM_RenderOneView/" + name + "/kinect640").c_str(),
                                     BM_RenderOneView, s, false)
            ->Unit(benchmark::kMicrosecond);
        benchmark::RegisterBenchmark(("BM_RenderOneView/" + name + "/pcl150").c_str(),
                                     BM_RenderOneView, s, true)
            ->Unit(benchmark::kMicrosecond);
        benchmark::RegisterBenchmark(("BM_BuildRenderer/" + name).c_str(), BM_BuildRenderer, s)
            ->Unit(benchmark::kMillisecond);
    }
    benchmark::RegisterBenchmark("BM_RenderScene", BM_RenderScene)
        ->Arg(1)
        ->Arg(2)
        ->ArgName("threads")
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
}

}  // namespace

int main(int argc, char** argv) {
    register_all();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
