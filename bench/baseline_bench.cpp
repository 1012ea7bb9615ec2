// Time per cloud of every registered global descriptor (make_descriptor) on three real object
// clouds of different sizes, single thread. Real clouds come from $ESF_DATA (default
// ../shared/data beside the repository); a missing file skips its benchmarks with a message.
//
//   build/bench/baseline_bench --benchmark_min_time=1
//
// The name reads BM_Descriptor/<descriptor>/<cloud>:<points>; the PCL baselines include their
// preprocessing (mesh resolution, voxel grid, outlier removal, normals).

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_data.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/io/cloud_io.hpp"

namespace {

using esf::bench::data_dir;

// A Kinect mug (stereo scene), a large box front and a small box far away.
const std::vector<std::string> kClouds = {
    "real/objects/pcl_mugscene_o1.pcd",
    "real/objects/mosd_learn0_o2.pcd",
    "real/objects/mosd_learn7_o3.pcd",
};

void register_all() {
    for (const auto& relative : kClouds) {
        const std::filesystem::path file = data_dir() / relative;
        esf::Points points;
        std::string error;
        try {
            points = esf::drop_non_finite(esf::read_cloud(file.string()).points).points;
        } catch (const std::exception& e) {
            error = std::string("cannot read shared data (set ESF_DATA): ") + e.what();
        }
        const std::string cloud = file.stem().string() + ":" + std::to_string(points.size());
        for (const auto& name : esf::descriptor_names()) {
            benchmark::RegisterBenchmark(("BM_Descriptor/" + name + "/" + cloud).c_str(),
                                         [name, points, error](benchmark::State& state) {
                                             if (!error.empty()) {
                                                 state.SkipWithError(error.c_str());
                                                 return;
                                             }
                                             const auto descriptor = esf::make_descriptor(name);
                                             std::size_t signatures = 0;
                                             for (auto _ : state) {
                                                 auto result = descriptor->compute(points);
                                                 signatures = result.size();
                                                 benchmark::DoNotOptimize(result);
                                             }
                                             state.SetItemsProcessed(state.iterations());
                                             state.counters["signatures"] =
                                                 static_cast<double>(signatures);
                                         })
                ->Unit(benchmark::kMillisecond);
        }
    }
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
