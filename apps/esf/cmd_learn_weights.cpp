// esf learn-weights DB : learns the weights of a descriptor's sub-histograms (ESF's ten, and
// esf-angles' six surface angle histograms besides) on the database's synthetic views
// (leave-one-model-out) and stores them with the database.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "cli_evaluate.hpp"
#include "commands.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/evaluation/evaluation.hpp"
#include "esf/evaluation/weight_learning.hpp"
#include "esf/training/database.hpp"

namespace esf::cli {

namespace {

struct LearnArgs {
    std::string database;
    std::string descriptor;
    std::string groups;
    std::size_t max_queries = 3000;
    int iterations = 12;
    double smooth = WeightLearningOptions{}.smooth;
    double step = WeightLearningOptions{}.initial_step;
    bool per_sample = false;
    std::size_t k = 10;
    int threads = 0;
    bool dry_run = false;
    bool json = false;
};

void run_learn_weights(const LearnArgs& args) {
    const auto start = std::chrono::steady_clock::now();
    // The file must exist (a writer would create it) and, unless --dry-run, be writable and not
    // in training: checked before learning. The writer is held until the weights are stored,
    // so the database cannot change in between (and set_weights checks that it did not).
    std::optional<Database> writer;
    std::string learned_on;
    DescriptorMatrix matrix;
    {
        const Database db(args.database, OpenMode::kRead);
        if (!args.dry_run) writer.emplace(args.database, OpenMode::kWrite);
        matrix = db.load_descriptors(args.descriptor);
        learned_on = db.content_fingerprint(matrix.kind.name);
    }
    const DescriptorInfo info = descriptor_info(matrix.kind.name);
    if (descriptor_blocks(info).size() < 2)
        throw std::invalid_argument(args.database + ": " + matrix.kind.name +
                                    " has a single block: no block weights to learn");
    WeightLearningOptions options;
    options.groups = cli_model_groups(matrix, args.groups);
    options.max_queries = args.max_queries;
    options.max_iterations = args.iterations;
    options.threads = args.threads;
    options.smooth = args.smooth;
    options.initial_step = args.step;
    options.trust_region = std::max(options.trust_region, args.step);
    options.class_balanced = !args.per_sample;
    Progress progress("learn-weights", static_cast<std::size_t>(args.iterations));
    options.progress = [&](int iteration, double objective) {
        progress.update(static_cast<std::size_t>(iteration),
                        "objective " + std::to_string(objective));
    };
    const WeightLearningResult learned = learn_weights(matrix, options);
    progress.finish();

    // The gain on every view (not only the queries learning used), with k nearest views.
    SyntheticOptions eval;
    eval.k = args.k;
    eval.threads = args.threads;
    eval.groups = options.groups;
    const EvaluationReport before = evaluate_synthetic(matrix, eval);
    eval.weights = descriptor_dimension_weights(info, learned.weights);
    const EvaluationReport after = evaluate_synthetic(matrix, eval);

    if (writer) writer->set_weights(learned.weights, matrix.kind.name, learned_on);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::vector<std::string>& names = info.block_names;
    const std::string protocol =
        options.groups.empty() ? "leave-one-model-out" : "leave-one-group-out";
    if (args.json) {
        nlohmann::json weights = nlohmann::json::object();
        for (std::size_t b = 0; b < learned.weights.size(); ++b)
            weights[names[b]] = learned.weights[b];
        nlohmann::json out = {{"database", args.database},
                              {"descriptor", matrix.kind.name},
                              {"weights", learned.weights},
                              {"block_weights", weights},
                              {"stored", !args.dry_run},
                              {"protocol", protocol},
                              {"queries", learned.queries},
                              {"iterations", learned.iterations},
                              {"accepted", learned.accepted},
                              {"objective_before", learned.objective_before},
                              {"objective_after", learned.objective_after},
                              {"history", learned.history},
                              {"k", args.k},
                              {"synthetic_before",
                               {{"samples", before.samples},
                                {"top1", before.top1},
                                {"top10", before.topk},
                                {"class_top1", before.class_top1},
                                {"class_top10", before.class_topk}}},
                              {"synthetic_after",
                               {{"samples", after.samples},
                                {"top1", after.top1},
                                {"top10", after.topk},
                                {"class_top1", after.class_top1},
                                {"class_top10", after.class_topk}}},
                              {"seconds", seconds}};
        std::cout << out.dump(2) << '\n';
    } else {
        std::printf("%s weights (%s, %zu of %zu views as queries):\n", matrix.kind.name.c_str(),
                    protocol.c_str(), learned.queries, after.samples);
        for (std::size_t b = 0; b < learned.weights.size(); ++b)
            std::printf("  %-9s %.4f\n", names[b].c_str(), static_cast<double>(learned.weights[b]));
        std::printf("objective %.4f -> %.4f (%d iterations, %d accepted)\n",
                    learned.objective_before, learned.objective_after, learned.iterations,
                    learned.accepted);
        const std::string k = std::to_string(args.k) + "-NN";
        std::printf("synthetic 1-NN per sample %s%% -> %s%% (%+.1f), per class %s%% -> %s%%\n",
                    percent_text(before.top1).c_str(), percent_text(after.top1).c_str(),
                    100.0 * (after.top1 - before.top1), percent_text(before.class_top1).c_str(),
                    percent_text(after.class_top1).c_str());
        std::printf("synthetic %s per sample %s%% -> %s%% (%+.1f), per class %s%% -> %s%%\n",
                    k.c_str(), percent_text(before.topk).c_str(), percent_text(after.topk).c_str(),
                    100.0 * (after.topk - before.topk), percent_text(before.class_topk).c_str(),
                    percent_text(after.class_topk).c_str());
        std::printf("%s in %s (%.1f s)\n", args.dry_run ? "not stored (--dry-run)" : "stored",
                    args.database.c_str(), seconds);
    }
    std::cout.flush();
    if (!std::cout) throw std::runtime_error("writing the output failed");
}

}  // namespace

void add_learn_weights_command(CLI::App& app) {
    auto args = std::make_shared<LearnArgs>();
    CLI::App* cmd = add_command(
        app, "learn-weights", "Learn the weights of a descriptor's sub-histograms",
        "Learn the weights of a descriptor's sub-histograms (ESF's ten: D2, D3, A3 and their\n"
        "IN/OUT/MIXED splits, D2 ratio; esf-angles adds its six surface angle histograms)\n"
        "on the database's own synthetic views, leave-one-model-out (with\n"
        "--groups: leave-one-group-out), and store them with the database; esf classify, scene\n"
        "and eval then use them (--no-weights there ignores them). The objective is the 1-NN\n"
        "accuracy (mean over classes) of up to --max-queries evenly spaced views plus a small\n"
        "margin term; a deterministic pattern search over the log-weights only accepts steps\n"
        "that raise it.\n"
        "Prints the weights, the objective and the synthetic 1-NN / k-NN accuracy over all\n"
        "views before and after; --json prints them as one object.");
    cmd->add_option("database", args->database, "Training database (esf train ... -o DB)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--descriptor", args->descriptor,
                    "Descriptor kind when the database holds several (esf, esf-angles, ...)");
    cmd->add_option("--groups", args->groups,
                    "Catalog CSV (file, group columns): models of a group are left out together")
        ->check(CLI::ExistingFile);
    cmd->add_option("--max-queries", args->max_queries,
                    "Views used as queries while learning, evenly spaced (0 = all)")
        ->capture_default_str();
    cmd->add_option("--iterations", args->iterations,
                    "Most exact leave-one-model-out searches after the first")
        ->check(CLI::Range(0, 1000))
        ->capture_default_str();
    cmd->add_option("--smooth", args->smooth,
                    "Weight of the margin term that breaks ties between equally accurate weights")
        ->check(CLI::Range(0.0, 10.0))
        ->capture_default_str();
    cmd->add_option("--step", args->step, "First step on a log-weight (halved down to 0.03)")
        ->check(CLI::Range(0.05, 5.0))
        ->capture_default_str();
    cmd->add_flag("--per-sample", args->per_sample,
                  "Maximise the 1-NN accuracy per sample (default: the mean of the per-class "
                  "accuracies, so that large categories do not dominate)");
    cmd->add_option("-k", args->k, "Nearest views for the k-NN accuracy printed before/after")
        ->check(CLI::Range(1, 1000))
        ->capture_default_str();
    add_threads_option(*cmd, args->threads);
    cmd->add_flag("--dry-run", args->dry_run, "Learn and print, but do not store the weights");
    cmd->add_flag("--json", args->json, "Print one JSON object instead of the text");
    cmd->callback([args] { run_learn_weights(*args); });
}

}  // namespace esf::cli
