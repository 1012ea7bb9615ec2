// Training throughput: render + describe views of the shared meshes (views/s), and the
// database's bulk write and load.
//
//   build/bench/training_bench [--benchmark_filter=...]
//   ESF_DATA=/path/to/shared/data overrides where the meshes are looked for.

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_data.hpp"
#include "esf/core/parallel.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/render/render.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"

namespace {

namespace fs = std::filesystem;

using esf::bench::data_dir;

/// A mix of the shared meshes: dense YCB scans (PLY) and light KIT models (OBJ).
const std::vector<std::string> kSample = {
    "meshes/can/ycb_002_master_chef_can.ply", "meshes/mug/ycb_025_mug.ply",
    "meshes/bottle/kit_CokePlasticLarge.obj", "meshes/box/kit_Amicelli.obj",
    "meshes/bowl/ycb_024_bowl.ply",           "meshes/box/kit_FruitTea.obj",
};

/// prefix + number (GCC 12 warns falsely about "literal" + std::to_string()).
std::string indexed(std::string prefix, int i) {
    prefix += std::to_string(i);
    return prefix;
}

fs::path temp_dir(const std::string& name) {
    const fs::path dir =
        fs::temp_directory_path() / ("esf_training_bench_" + std::to_string(getpid()) + "_" + name);
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

/// ROOT/<category>/<file> links to the sample meshes that exist; empty when none does.
fs::path sample_root() {
    const fs::path root = temp_dir("root");
    for (const auto& rel : kSample) {
        const fs::path src = data_dir() / rel;
        if (!fs::exists(src)) continue;
        const fs::path dst = root / src.parent_path().filename() / src.filename();
        fs::create_directories(dst.parent_path());
        fs::create_symlink(fs::absolute(src), dst);
    }
    return fs::is_empty(root) ? fs::path() : root;
}

/// The whole pipeline (load, render, describe, store) on the sample meshes, all cores.
void BM_TrainSampleMeshes(benchmark::State& state) {
    const fs::path root = sample_root();
    if (root.empty()) {
        state.SkipWithError("shared meshes not found; set ESF_DATA");
        return;
    }
    const fs::path db_dir = temp_dir("db");
    std::size_t views = 0;
    int run = 0;
    for (auto _ : state) {
        esf::Database db((db_dir / (indexed("db", run++) + ".sqlite")).string(),
                         esf::OpenMode::kWrite);
        esf::TrainingOptions options;
        options.threads = static_cast<int>(state.range(0));
        const esf::TrainingResult r = esf::train(root.string(), db, options);
        views += r.views + r.views_skipped;
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(views));
    state.counters["views/s"] =
        benchmark::Counter(static_cast<double>(views), benchmark::Counter::kIsRate);
    fs::remove_all(root);
    fs::remove_all(db_dir);
}
BENCHMARK(BM_TrainSampleMeshes)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

/// Rendering alone: the 80 views of one mesh.
void BM_RenderViews(benchmark::State& state) {
    const fs::path file = data_dir() / kSample[static_cast<std::size_t>(state.range(0))];
    if (!fs::exists(file)) {
        state.SkipWithError("shared meshes not found; set ESF_DATA");
        return;
    }
    const esf::Mesh mesh = esf::load_mesh(file.string());
    std::size_t views = 0;
    for (auto _ : state) {
        const auto rendered = esf::render_views(mesh, esf::RenderOptions{});
        views += rendered.size();
        benchmark::DoNotOptimize(rendered.data());
    }
    state.SetLabel(file.filename().string());
    state.SetItemsProcessed(static_cast<std::int64_t>(views));
}
BENCHMARK(BM_RenderViews)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime();

/// ESF alone on rendered views, all cores.
void BM_DescribeViews(benchmark::State& state) {
    const fs::path file = data_dir() / kSample[0];
    if (!fs::exists(file)) {
        state.SkipWithError("shared meshes not found; set ESF_DATA");
        return;
    }
    const auto rendered = esf::render_views(esf::load_mesh(file.string()), esf::RenderOptions{});
    std::vector<esf::Points> clouds;
    std::size_t points = 0;
    for (const auto& v : rendered) {
        clouds.push_back(v.points);
        points += v.points.size();
    }
    for (auto _ : state) benchmark::DoNotOptimize(esf::compute_esf_batch(clouds).data());
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(clouds.size()));
    state.counters["points/view"] =
        static_cast<double>(points) / static_cast<double>(clouds.size());
}
BENCHMARK(BM_DescribeViews)->Unit(benchmark::kMillisecond)->UseRealTime();

/// A database the size of the shared set: 185 models x 80 views x 640 floats.
std::string synthetic_database(const fs::path& dir) {
    const std::string path = (dir / "synthetic.sqlite").string();
    esf::Database db(path, esf::OpenMode::kWrite);
    db.add_descriptor_kind({"esf", esf::kEsfVersion, esf::kEsfSize});
    for (int m = 0; m < 185; ++m) {
        esf::ModelEntry model;
        model.category = indexed("c", m % 28);
        model.name = indexed("m", m);
        for (int v = 0; v < 80; ++v) {
            esf::ViewEntry view;
            view.index = v;
            view.points = 1000;
            view.descriptors.assign(esf::kEsfSize, 1.0f / esf::kEsfSize);
            model.views.push_back(std::move(view));
        }
        db.write_model(model, "esf");
    }
    return path;
}

void BM_LoadDescriptors(benchmark::State& state) {
    const fs::path dir = temp_dir("load");
    const std::string path = synthetic_database(dir);
    std::size_t rows = 0;
    for (auto _ : state) {
        const esf::Database db(path);
        const auto matrix = db.load_descriptors();
        rows += matrix.rows();
        benchmark::DoNotOptimize(matrix.data.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(rows));
    state.counters["MB"] = static_cast<double>(fs::file_size(path)) / 1e6;
    fs::remove_all(dir);
}
BENCHMARK(BM_LoadDescriptors)->Unit(benchmark::kMillisecond)->UseRealTime();

/// One transaction per model of 80 views (what training commits), synchronous=FULL.
void BM_WriteModel(benchmark::State& state) {
    const fs::path dir = temp_dir("write");
    esf::Database db((dir / "db.sqlite").string(), esf::OpenMode::kWrite);
    db.add_descriptor_kind({"esf", esf::kEsfVersion, esf::kEsfSize});
    esf::ModelEntry model;
    model.category = "c";
    for (int v = 0; v < 80; ++v) {
        esf::ViewEntry view;
        view.index = v;
        view.descriptors.assign(esf::kEsfSize, 1.0f / esf::kEsfSize);
        model.views.push_back(std::move(view));
    }
    int i = 0;
    for (auto _ : state) {
        model.name = indexed("m", i++);
        db.write_model(model, "esf");
    }
    state.SetItemsProcessed(state.iterations() * 80);
    fs::remove_all(dir);
}
BENCHMARK(BM_WriteModel)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
