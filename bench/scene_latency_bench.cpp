// Latency of online recognition per stage on real organised table scenes (640 x 480, Kinect v1):
// segmentation, description of the clusters (in parallel), classification of the clusters (one
// batch, k-NN), and the whole frame: verified (the default, when the database stores the models'
// surfaces), verified without merging parts (frame_unmerged) and by k-NN only. The paper's
// target is a frame at 30 Hz (33 ms) on two cores.
//
//   scene_latency_bench [--db PATH] [--threads N] [--kernels best|avx512|avx2|portable]
//                       [benchmark flags]
//
// --db: a training database (default $ESF_BENCH_DB or /tmp/esf_all.sqlite, made with
// `esf train ../shared/data/meshes -o /tmp/esf_all.sqlite`). When it does not exist, a database
// of the same size (185 models x 80 views of random ESF-like descriptors) is written to
// /tmp/esf_bench_synthetic.sqlite once and used instead: the search cost then matches, the
// classes do not. --threads: worker threads for every stage (default 2). --kernels: the SIMD
// kernels of description and search (RecognizerOptions::kernels; avx2: what a CPU without
// AVX-512 runs; the same results).

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench_data.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/segmentation/segmentation.hpp"
#include "esf/training/database.hpp"

namespace fs = std::filesystem;

namespace {

int g_threads = 2;
esf::Kernels g_kernels = esf::Kernels::kBest;
std::unique_ptr<esf::Recognizer> g_recognizer;  // verifies when the database stores surfaces
std::unique_ptr<esf::Recognizer> g_knn_only;
std::unique_ptr<esf::Recognizer> g_unmerged;  // verifies, parts stay as segmented

/// 185 models x 80 views of random descriptors: ten blocks, each a smooth random bump, the
/// whole normalised to sum 1 (roughly the shape of real ESF histograms).
void write_synthetic_database(const std::string& path) {
    const std::string partial = path + ".partial";
    fs::remove(partial);
    {
        esf::Database db(partial, esf::OpenMode::kWrite);
        db.add_descriptor_kind({"esf", esf::kEsfVersion, esf::kEsfSize});
        std::mt19937_64 rng(2011);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        for (int m = 0; m < 185; ++m) {
            esf::ModelEntry model;
            model.category = "category_" + std::to_string(m % 28);
            model.name = "model_" + std::to_string(m);
            model.file = model.category + "/" + model.name + ".ply";
            for (int v = 0; v < 80; ++v) {
                esf::ViewEntry view;
                view.index = v;
                view.points = 5000;
                view.descriptors.resize(esf::kEsfSize);
                double sum = 0.0;
                for (int b = 0; b < esf::kEsfBlocks; ++b) {
                    const float centre = 64.0f * u(rng), width = 4.0f + 12.0f * u(rng);
                    for (int i = 0; i < esf::kEsfBins; ++i) {
                        const float x = (float(i) - centre) / width;
                        float& bin = view.descriptors[static_cast<std::size_t>(b * 64 + i)];
                        bin = std::exp(-x * x) + 0.02f * u(rng);
                        sum += bin;
                    }
                }
                for (float& bin : view.descriptors) bin = static_cast<float>(bin / sum);
                model.views.push_back(std::move(view));
            }
            db.write_model(model, "esf");
        }
    }  // closing the writer leaves one self-contained file
    fs::rename(partial, path);
}

esf::SegmentationOptions segmentation_options() {
    esf::SegmentationOptions options;
    options.threads = g_threads;
    return options;
}

void BM_Segment(benchmark::State& state, const esf::PointCloud* scene) {
    const esf::SegmentationOptions options = segmentation_options();
    std::size_t objects = 0;
    for (auto _ : state) {
        esf::SegmentationResult r = esf::segment_scene(*scene, options);
        objects = r.clusters.size();
        benchmark::DoNotOptimize(r);
    }
    state.counters["objects"] = static_cast<double>(objects);
    state.SetItemsProcessed(state.iterations());
}

void BM_Describe(benchmark::State& state, const esf::PointCloud* scene) {
    const esf::SegmentationResult segmentation = esf::segment_scene(*scene, segmentation_options());
    std::vector<esf::Points> clouds;
    std::size_t points = 0;
    for (const esf::Cluster& c : segmentation.clusters) {
        clouds.push_back(c.points);
        points += c.points.size();
    }
    for (auto _ : state) benchmark::DoNotOptimize(g_recognizer->describe_batch(clouds));
    state.counters["objects"] = static_cast<double>(clouds.size());
    state.counters["points"] = static_cast<double>(points);
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(clouds.size()));
}

void BM_Classify(benchmark::State& state, const esf::PointCloud* scene) {
    const esf::SegmentationResult segmentation = esf::segment_scene(*scene, segmentation_options());
    std::vector<esf::Points> clouds;
    for (const esf::Cluster& c : segmentation.clusters) clouds.push_back(c.points);
    const std::vector<esf::QueryDescriptor> descriptors = g_recognizer->describe_batch(clouds);
    for (auto _ : state) benchmark::DoNotOptimize(g_recognizer->classify_batch(descriptors));
    state.counters["objects"] = static_cast<double>(clouds.size());
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(clouds.size()));
}

void frame(benchmark::State& state, const esf::PointCloud* scene,
           const esf::Recognizer& recognizer) {
    const esf::SegmentationOptions options = segmentation_options();
    std::size_t objects = 0;
    for (auto _ : state) {
        esf::SceneRecognition r = recognizer.recognize_scene(*scene, options);
        objects = r.objects.size();
        benchmark::DoNotOptimize(r);
    }
    state.counters["objects"] = static_cast<double>(objects);
    state.counters["fps"] =
        benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.SetItemsProcessed(state.iterations());
}

/// The whole frame as esf scene runs it: verified when the database stores model surfaces.
void BM_Frame(benchmark::State& state, const esf::PointCloud* scene) {
    frame(state, scene, *g_recognizer);
}

/// The whole frame verified, without merging parts (--no-merge-parts).
void BM_FrameUnmerged(benchmark::State& state, const esf::PointCloud* scene) {
    frame(state, scene, *g_unmerged);
}

/// The whole frame by k-NN only (--no-verify).
void BM_FrameKnnOnly(benchmark::State& state, const esf::PointCloud* scene) {
    frame(state, scene, *g_knn_only);
}

}  // namespace

int main(int argc, char** argv) {
    std::string db_path =
        std::getenv("ESF_BENCH_DB") ? std::getenv("ESF_BENCH_DB") : "/tmp/esf_all.sqlite";
    std::vector<char*> rest = {argv[0]};
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--db" && i + 1 < argc)
            db_path = argv[++i];
        else if (arg == "--threads" && i + 1 < argc)
            g_threads = std::atoi(argv[++i]);
        else if (arg == "--kernels" && i + 1 < argc)
            g_kernels = esf::parse_enum<esf::Kernels>(argv[++i]);
        else
            rest.push_back(argv[i]);
    }
    int rest_count = static_cast<int>(rest.size());
    benchmark::Initialize(&rest_count, rest.data());

    if (!fs::exists(db_path)) {
        const std::string synthetic =
            (fs::temp_directory_path() / "esf_bench_synthetic.sqlite").string();
        std::fprintf(stderr, "%s missing: using a synthetic database of the same size, %s\n",
                     db_path.c_str(), synthetic.c_str());
        if (!fs::exists(synthetic)) write_synthetic_database(synthetic);
        db_path = synthetic;
    }
    esf::RecognizerOptions options;
    options.threads = g_threads;
    options.kernels = g_kernels;
    g_recognizer = std::make_unique<esf::Recognizer>(db_path, options);
    options.merge_parts = false;
    g_unmerged = std::make_unique<esf::Recognizer>(db_path, options);
    options.verify = false;
    g_knn_only = std::make_unique<esf::Recognizer>(db_path, options);
    const esf::RecognizerInfo& info = g_recognizer->info();
    std::fprintf(stderr,
                 "database %s: %zu views of %zu models, %s samples %d, threads %d, kernels %s, "
                 "verification: %s\n",
                 db_path.c_str(), info.views, info.models, info.setup.kind.name.c_str(),
                 info.setup.esf.samples, g_threads, esf::to_string(g_kernels),
                 info.verification.c_str());

    const fs::path scenes_dir = esf::bench::data_dir() / "real" / "scenes";
    std::vector<std::pair<std::string, std::unique_ptr<esf::PointCloud>>> scenes;
    if (fs::is_directory(scenes_dir))
        for (const auto& entry : fs::directory_iterator(scenes_dir)) {
            const std::string name = entry.path().filename().string();
            if (name.rfind("mosd_learn", 0) == 0 && entry.path().extension() == ".pcd")
                scenes.emplace_back(
                    entry.path().stem().string(),
                    std::make_unique<esf::PointCloud>(esf::read_cloud(entry.path().string())));
        }
    std::sort(scenes.begin(), scenes.end());
    if (scenes.empty()) {
        std::fprintf(stderr, "no scenes in %s\n", scenes_dir.string().c_str());
        return 1;
    }
    for (const auto& [name, cloud] : scenes) {
        const esf::PointCloud* scene = cloud.get();
        for (const auto& [stage, fn] : std::vector<
                 std::pair<std::string, void (*)(benchmark::State&, const esf::PointCloud*)>>{
                 {"segment", BM_Segment},
                 {"describe", BM_Describe},
                 {"classify", BM_Classify},
                 {"frame", BM_Frame},
                 {"frame_unmerged", BM_FrameUnmerged},
                 {"frame_knn_only", BM_FrameKnnOnly}})
            benchmark::RegisterBenchmark((stage + "/" + name).c_str(), fn, scene)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
    }
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    g_recognizer.reset();
    g_knn_only.reset();
    g_unmerged.reset();
    return 0;
}
