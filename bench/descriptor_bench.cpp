// Google Benchmark of the ESF descriptor (and the surface angles of esf-angles): one cloud per
// iteration, single thread, and the batch API on all cores. Real clouds come from $ESF_DATA
// (default ../shared/data) when present; a generated partial cylinder is always measured.

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>

#include "bench_data.hpp"
#include "descriptors/esf/esf_trace.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/descriptors/primitive_fit.hpp"
#include "esf/descriptors/surface_angles.hpp"
#include "esf/io/cloud_io.hpp"

namespace {

/// Front half of a cylinder (r 4 cm, h 12 cm) with 1 mm noise: what a depth camera sees of a can.
esf::Points partial_cylinder(std::size_t count) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> angle(0.0f, 3.14159f), height(0.0f, 0.12f);
    std::normal_distribution<float> noise(0.0f, 0.001f);
    esf::Points points(count);
    for (auto& p : points) {
        const float a = angle(rng);
        p = {0.04f * std::cos(a) + noise(rng), height(rng), 0.04f * std::sin(a) + noise(rng)};
    }
    return points;
}

void BM_EsfFastCylinder(benchmark::State& state) {
    const esf::Points points = partial_cylinder(static_cast<std::size_t>(state.range(0)));
    esf::EsfEstimator estimator;
    for (auto _ : state) benchmark::DoNotOptimize(estimator.compute(points));
    state.SetItemsProcessed(state.iterations());
    state.SetLabel(esf::detail::trace_kernel_name());
}
BENCHMARK(BM_EsfFastCylinder)->Arg(2000)->Arg(15000)->Arg(100000)->Unit(benchmark::kMillisecond);

void BM_EsfPclSamplerCylinder(benchmark::State& state) {
    const esf::Points points = partial_cylinder(15000);
    esf::EsfOptions options;
    options.sampler = esf::EsfSampler::kPcl;
    esf::EsfEstimator estimator(options);
    for (auto _ : state) benchmark::DoNotOptimize(estimator.compute(points));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EsfPclSamplerCylinder)->Unit(benchmark::kMillisecond);

/// The real view milk_test.pcd (finite points), or none after marking `state` skipped when the
/// shared data is missing.
esf::Points milk_view(benchmark::State& state) {
    const std::filesystem::path file = esf::bench::data_dir() / "real/pcl/milk_test.pcd";
    if (!std::filesystem::exists(file)) {
        state.SkipWithError(("shared data missing: " + file.string() + " (set ESF_DATA)").c_str());
        return {};
    }
    return esf::drop_non_finite(esf::read_cloud(file.string()).points).points;
}

void BM_EsfFastRealMilk(benchmark::State& state) {
    const esf::Points points = milk_view(state);
    if (points.empty()) return;
    esf::EsfEstimator estimator;
    for (auto _ : state) benchmark::DoNotOptimize(estimator.compute(points));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EsfFastRealMilk)->Unit(benchmark::kMillisecond);

void BM_SurfaceAnglesCylinder(benchmark::State& state) {
    const esf::Points points = partial_cylinder(static_cast<std::size_t>(state.range(0)));
    for (auto _ : state) benchmark::DoNotOptimize(esf::compute_surface_angles(points));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SurfaceAnglesCylinder)
    ->Arg(2000)
    ->Arg(15000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond);

void BM_SurfaceAnglesRealMilk(benchmark::State& state) {
    const esf::Points points = milk_view(state);
    if (points.empty()) return;
    for (auto _ : state) benchmark::DoNotOptimize(esf::compute_surface_angles(points));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SurfaceAnglesRealMilk)->Unit(benchmark::kMillisecond);

void BM_PrimitiveFitCylinder(benchmark::State& state) {
    const esf::Points points = partial_cylinder(static_cast<std::size_t>(state.range(0)));
    for (auto _ : state) benchmark::DoNotOptimize(esf::fit_primitives(points));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PrimitiveFitCylinder)->Arg(2000)->Arg(15000)->Unit(benchmark::kMillisecond);

void BM_PrimitiveFitRealMilk(benchmark::State& state) {
    const esf::Points points = milk_view(state);
    if (points.empty()) return;
    for (auto _ : state) benchmark::DoNotOptimize(esf::fit_primitives(points));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PrimitiveFitRealMilk)->Unit(benchmark::kMillisecond);

/// The whole default signature (ESF, surface angles, cylinder-box) of a real view.
void BM_EsfAnglesRealMilk(benchmark::State& state) {
    const esf::Points points = milk_view(state);
    if (points.empty()) return;
    const auto descriptor = esf::make_descriptor("esf-angles");
    for (auto _ : state) benchmark::DoNotOptimize(descriptor->compute(points));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EsfAnglesRealMilk)->Unit(benchmark::kMillisecond);

void BM_EsfBatchAllCores(benchmark::State& state) {
    std::vector<esf::Points> clouds(64, partial_cylinder(15000));
    for (auto _ : state) benchmark::DoNotOptimize(esf::compute_esf_batch(clouds));
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(clouds.size()));
}
BENCHMARK(BM_EsfBatchAllCores)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
