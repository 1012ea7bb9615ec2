// esf describe FILE... : ESF descriptors of point-cloud files, as CSV or JSON.

#include <atomic>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "commands.hpp"
#include "core/atomic_file.hpp"
#include "core/number_text.hpp"
#include "esf/core/parallel.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/io/cloud_io.hpp"

namespace esf::cli {

namespace {

struct DescribeArgs {
    std::vector<std::string> files;
    EsfOptions esf;  ///< --seed, --samples, --grid, --sampler
    int threads = 0;
    std::string format = "csv";
    std::string output;
};

void run_describe(const DescribeArgs& args) {
    const EsfOptions& options = args.esf;
    EsfEstimator{options};  // validates the options before any file is read

    // Read and describe every file in parallel; each file's outcome goes to its own slot.
    struct Item {
        EsfResult result;
        std::string error;
    };
    std::vector<Item> items(args.files.size());
    const int slots = resolve_threads(args.threads);
    std::vector<EsfEstimator> estimators;
    for (int i = 0; i < slots; ++i) estimators.emplace_back(options);
    // Each slot's points, their memory reused from file to file.
    std::vector<Points> slot_points(static_cast<std::size_t>(slots));
    Progress progress("describe", args.files.size());
    std::atomic<std::size_t> done{0};
    parallel_for_slots(args.files.size(), slots, [&](std::size_t i, int slot) {
        try {
            EsfEstimator& estimator = estimators[static_cast<std::size_t>(slot)];
            Points& points = slot_points[static_cast<std::size_t>(slot)];
            const std::size_t dropped = read_finite_points(args.files[i], points);
            require_esf_points(points.size(), dropped);
            items[i].result = estimator.compute(points);
            items[i].result.dropped_points = dropped;
        } catch (const std::exception& e) {
            const std::string what = e.what();
            items[i].error = what.rfind(args.files[i], 0) == 0 ? what : args.files[i] + ": " + what;
        }
        ++done;
        if (slot == 0) progress.update(done.load());
    });
    progress.finish();

    // The whole output, then to standard output or, replacing it at once, to the output file.
    std::string text;
    int failed = 0;
    nlohmann::json json = nlohmann::json::array();
    for (std::size_t i = 0; i < items.size(); ++i) {
        if (!items[i].error.empty()) {
            std::fprintf(stderr, "esf: error: %s\n", items[i].error.c_str());
            ++failed;
            continue;
        }
        const auto& d = items[i].result.descriptor;
        if (args.format == "json") {
            nlohmann::json entry;
            entry["file"] = args.files[i];
            entry["points"] = items[i].result.points;
            entry["dropped_points"] = items[i].result.dropped_points;
            entry["descriptor"] = std::vector<float>(d.begin(), d.end());
            json.push_back(std::move(entry));
        } else {
            text += args.files[i];
            for (float v : d) {
                text += ',';
                detail::append_float(text, v);
            }
            text += '\n';
        }
    }
    if (args.format == "json") text += json.dump(1) + '\n';
    if (args.output.empty()) {
        std::cout << text;
        std::cout.flush();
        if (!std::cout) throw std::runtime_error("writing the output failed");
    } else {
        detail::write_file_atomically(args.output, text);
    }
    if (failed) throw ExitStatus{kExitRuntime};
}

}  // namespace

void add_describe_command(CLI::App& app) {
    auto args = std::make_shared<DescribeArgs>();
    CLI::App* cmd = add_command(
        app, "describe", "Compute the 640-bin ESF descriptor of point-cloud files",
        "Compute the 640-bin ESF descriptor of point-cloud files (PCD, PLY, x y z text).\n"
        "Non-finite points are dropped first. CSV: one line per file, path,v0,...,v639.");
    cmd->add_option("files", args->files, "Point-cloud files (.pcd, .ply, .xyz/.txt)")->required();
    add_seed_option(*cmd, args->esf.seed, "Random seed; same seed, same descriptor");
    cmd->add_option("--samples", args->esf.samples, "Point triples sampled (the paper's number)")
        ->capture_default_str();
    cmd->add_option("--grid", args->esf.grid_size, "Voxel grid side, 8..64 (paper: 64)")
        ->capture_default_str();
    add_enum_option(*cmd, "--sampler", args->esf.sampler,
                    "fast or pcl (bit-exact pcl::ESFEstimation for srand(seed))");
    add_threads_option(*cmd, args->threads);
    cmd->add_option("--format", args->format, "Output format: csv or json")
        ->check(CLI::IsMember({"csv", "json"}))
        ->capture_default_str();
    cmd->add_option("-o,--output", args->output, "Write to this file instead of stdout");
    cmd->callback([args] { run_describe(*args); });
}

}  // namespace esf::cli
