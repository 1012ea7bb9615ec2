// esf_bench_descriptor FILE... : pcl::ESFEstimation and esf's ESF on the same clouds, in one
// process, single thread. Ends with "ratio: X" = PCL time / esf (fast sampler) time.

#include <pcl/features/esf.h>
#include <pcl/point_types.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/io/cloud_io.hpp"

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

template <typename F>
double best_of(int repeats, F&& f) {
    double best = 1e300;
    for (int r = 0; r < repeats; ++r) {
        const auto start = std::chrono::steady_clock::now();
        f();
        best = std::min(best, seconds_since(start));
    }
    return best;
}

}  // namespace

int main(int argc, char** argv) {
    int repeats = 5;
    esf::EsfOptions fast_options;
    std::vector<std::string> files;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--repeats" && i + 1 < argc) {
            repeats = std::atoi(argv[++i]);
        } else if (arg == "--kernels" && i + 1 < argc) {
            try {
                fast_options.kernels = esf::parse_enum<esf::Kernels>(argv[++i]);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "esf_bench_descriptor: %s\n", e.what());
                return 1;
            }
        } else if (arg == "-h" || arg == "--help") {
            std::printf(
                "usage: esf_bench_descriptor [--repeats N] [--kernels best|avx512|avx2|portable] "
                "FILE...\n"
                "Times pcl::ESFEstimation and esf (fast and pcl samplers) on each cloud,\n"
                "single thread, best of N runs; ends with 'ratio: PCL time / esf time'.\n"
                "--kernels avx2 runs the fast sampler as a CPU without AVX-512 would.\n");
            return 0;
        } else {
            files.push_back(arg);
        }
    }
    if (files.empty()) {
        std::fprintf(stderr, "esf_bench_descriptor: no input files (try --help)\n");
        return 1;
    }
    double total_pcl = 0.0, total_fast = 0.0, total_pcl_sampler = 0.0;
    std::printf("%-40s %8s %10s %10s %10s %8s\n", "file", "points", "pcl ms", "esf ms",
                "esf-pcl ms", "ratio");
    esf::EsfEstimator fast(fast_options);  // reused workspace, as a long-running process would
    esf::EsfOptions pcl_options;
    pcl_options.sampler = esf::EsfSampler::kPcl;
    esf::EsfEstimator pcl_sampler(pcl_options);
    for (const auto& file : files) {
        const esf::Points points = esf::drop_non_finite(esf::read_cloud(file).points).points;
        pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
        for (const auto& p : points) cloud->emplace_back(p.x(), p.y(), p.z());
        pcl::ESFEstimation<pcl::PointXYZ, pcl::ESFSignature640> reference;
        reference.setInputCloud(cloud);
        pcl::PointCloud<pcl::ESFSignature640> out;
        const double t_pcl = best_of(repeats, [&] { reference.compute(out); });
        volatile float sink = 0.0f;
        const double t_fast =
            best_of(repeats, [&] { sink = sink + fast.compute(points).descriptor[0]; });
        const double t_pcl_sampler =
            best_of(repeats, [&] { sink = sink + pcl_sampler.compute(points).descriptor[0]; });
        total_pcl += t_pcl, total_fast += t_fast, total_pcl_sampler += t_pcl_sampler;
        std::string name = file.size() > 40 ? "..." + file.substr(file.size() - 37) : file;
        std::printf("%-40s %8zu %10.3f %10.3f %10.3f %8.1f\n", name.c_str(), points.size(),
                    1e3 * t_pcl, 1e3 * t_fast, 1e3 * t_pcl_sampler, t_pcl / t_fast);
    }
    const double n = static_cast<double>(files.size());
    std::printf("mean per cloud: pcl %.3f ms, esf %.3f ms, esf --sampler pcl %.3f ms\n",
                1e3 * total_pcl / n, 1e3 * total_fast / n, 1e3 * total_pcl_sampler / n);
    std::printf("kernels: %s\n", esf::to_string(fast_options.kernels));
    std::printf("ratio: %.1f\n", total_pcl / total_fast);
    return 0;
}
