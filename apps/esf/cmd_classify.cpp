// esf classify DB CLOUD... : the class, model and view of segmented object clouds.

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "cli_recognize.hpp"
#include "commands.hpp"
#include "esf/core/parallel.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/recognizer.hpp"

namespace esf::cli {

namespace {

struct ClassifyArgs {
    RecognizerArgs recognizer;
    std::vector<std::string> files;
    bool json = false;
};

void run_classify(const ClassifyArgs& args) {
    const Recognizer recognizer(args.recognizer.database, recognizer_options(args.recognizer));
    if (!args.recognizer.no_weights)
        warn_if_weights_stale(args.recognizer.database, recognizer.info().setup.kind.name);
    warn_if_unverified(recognizer);
    const std::size_t n = args.files.size();

    // Read and describe every file in parallel (one cloud in memory per worker), then classify
    // the descriptors as one batch.
    std::vector<QueryDescriptor> descriptors(n);
    Progress progress("classify", n);
    std::atomic<std::size_t> done{0};
    parallel_for_slots(n, recognizer.options().threads, [&](std::size_t i, int slot) {
        try {
            descriptors[i] = recognizer.describe(read_cloud(args.files[i]).points);
        } catch (const std::exception& e) {
            descriptors[i].error = e.what();
        }
        ++done;
        if (slot == 0) progress.update(done.load());
    });
    progress.finish();
    std::vector<CloudClassification> results = recognizer.classify_batch(descriptors);
    if (recognizer.verifies()) {
        // Verification needs the points again: read each classified file once more.
        parallel_for(n, recognizer.options().threads, [&](std::size_t i) {
            if (!results[i].ok()) return;
            try {
                const Points points = drop_non_finite(read_cloud(args.files[i]).points).points;
                recognizer.verify(results[i].classification, Observation{points, nullptr});
            } catch (const std::exception& e) {
                results[i].error = e.what();
            }
        });
    }

    int failed = 0;
    for (std::size_t i = 0; i < n; ++i)
        if (!results[i].ok()) {
            std::fprintf(stderr, "esf: error: %s\n",
                         with_file(args.files[i], results[i].error).c_str());
            ++failed;
        }

    if (args.json) {
        nlohmann::json out = nlohmann::json::array();
        for (std::size_t i = 0; i < n; ++i) {
            if (!results[i].ok()) continue;
            nlohmann::json entry;
            entry["file"] = args.files[i];
            add_classification_json(entry, results[i].classification);
            out.push_back(std::move(entry));
        }
        std::cout << out.dump(2) << '\n';
    } else if (failed < static_cast<int>(n)) {
        std::size_t file_width = 4, class_width = 5, model_width = 5;
        for (std::size_t i = 0; i < n; ++i) {
            if (!results[i].ok()) continue;
            file_width = std::max(file_width, args.files[i].size());
            class_width = std::max(class_width, results[i].classification.class_name.size());
            model_width = std::max(model_width, results[i].classification.best_model.size());
        }
        const int fw = static_cast<int>(file_width), cw = static_cast<int>(class_width),
                  mw = static_cast<int>(model_width);
        std::printf("%-*s  %-*s  %10s  %-*s  %4s  %8s\n", fw, "file", cw, "class", "confidence", mw,
                    "model", "view", "distance");
        for (std::size_t i = 0; i < n; ++i) {
            if (!results[i].ok()) continue;
            const Classification& c = results[i].classification;
            std::printf("%-*s  %-*s  %10.2f  %-*s  %4d  %8.4f%s\n", fw, args.files[i].c_str(), cw,
                        c.class_name.c_str(), c.confidence, mw, c.best_model.c_str(), c.best_view,
                        c.best_distance, fit_text(c).c_str());
        }
    }
    std::cout.flush();
    if (!std::cout) throw std::runtime_error("writing the output failed");
    if (failed) throw ExitStatus{kExitRuntime};
}

}  // namespace

void add_classify_command(CLI::App& app) {
    auto args = std::make_shared<ClassifyArgs>();
    CLI::App* cmd = add_command(
        app, "classify", "Classify object clouds against a training database",
        "Classify object clouds (one object per file, e.g. the clusters of esf segment) against\n"
        "a training database: each cloud is described with the database's descriptor and\n"
        "settings, its k nearest views (L1) vote, and the table shows the winning class, its\n"
        "share of the votes (confidence), and the model, view and distance of its nearest view.\n"
        "--json prints an array of {file, class, confidence, model, view, distance, pose,\n"
        "neighbours: [{class, model, view, distance, pose}, ...]}, poses (model -> camera) as 16\n"
        "numbers row-major. A file that cannot be read or described is reported on stderr and\n"
        "the others go on; the exit status is then 2.");
    add_recognizer_options(*cmd, args->recognizer);
    cmd->add_option("clouds", args->files, "Object point clouds (.pcd, .ply, .xyz)")->required();
    cmd->add_flag("--json", args->json, "Print JSON instead of the table");
    cmd->callback([args] { run_classify(*args); });
}

}  // namespace esf::cli
