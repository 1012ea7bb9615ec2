// esf demo: the main job on an embedded default, offline, with nothing to download.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <random>

#include "cli_common.hpp"
#include "commands.hpp"
#include "esf/cloud_io.hpp"
#include "esf/esf_descriptor.hpp"

namespace esf::cli {

namespace {

struct DemoArgs {
    std::uint64_t seed = 1;
    std::string report;
};

/// What a depth camera sees of a mug-like cylinder (front half, with the rim), in metres.
PointCloud generated_view(std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::normal_distribution<float> noise(0.0f, 0.0015f);
    PointCloud cloud;
    for (int i = 0; i < 12000; ++i) {
        const float a = 3.14159265f * unit(rng);
        cloud.points.emplace_back(0.045f * std::cos(a) + noise(rng), -0.1f * unit(rng),
                                  0.8f - 0.045f * std::sin(a) + noise(rng));
    }
    cloud.width = static_cast<std::uint32_t>(cloud.points.size());
    return cloud;
}

void run_demo(const DemoArgs& args) {
    const auto dir = std::filesystem::temp_directory_path() / "esf-demo";
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "generated_view.pcd").string();
    write_pcd(path, generated_view(args.seed));
    const PointCloud cloud = read_cloud(path);
    EsfOptions options;
    options.seed = args.seed;
    const EsfResult result = compute_esf(cloud.points, options);
    std::printf("esf demo: described %s (%zu points)\n", path.c_str(), result.points);
    std::printf("%-10s %s\n", "block", "share of the descriptor");
    for (int b = 0; b < kEsfBlocks; ++b) {
        double sum = 0.0;
        for (int i = 0; i < kEsfBins; ++i)
            sum += result.descriptor[static_cast<std::size_t>(b * kEsfBins + i)];
        std::printf("%-10s %.4f %s\n", esf_block_names()[static_cast<std::size_t>(b)], sum,
                    std::string(static_cast<std::size_t>(sum * 120), '#').c_str());
    }
}

}  // namespace

void add_demo_command(CLI::App& app) {
    auto args = std::make_shared<DemoArgs>();
    CLI::App* cmd = app.add_subcommand("demo", "Run the main job on generated data (no download).");
    cmd->add_option("--seed", args->seed, "Random seed")->capture_default_str();
    cmd->add_option("--report", args->report, "Folder for a report (reserved)");
    cmd->callback([args] { run_demo(*args); });
}

}  // namespace esf::cli
