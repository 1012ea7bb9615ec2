// esf compare ROOT TESTSET.csv : train one database per descriptor on the same rendered views,
// evaluate each on the real test set and leave-one-model-out on its synthetic views, and print
// one table (the paper's comparison of ESF with its baselines, Sec. V).

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "commands.hpp"
#include "core/elapsed_time.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/evaluation/evaluation.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"

namespace esf::cli {

namespace {

struct CompareArgs {
    std::string root;
    std::string test_set;
    std::vector<std::string> descriptors;
    std::string work = "esf-compare";
    int level = 1;
    std::size_t k = 10;
    std::string groups;
    std::size_t max_queries = 0;
    std::uint64_t seed = 0;
    int threads = 0;
    bool json = false;
};

/// One row of the table: what a descriptor achieved, or why it has no result.
struct CompareRow {
    std::string descriptor;
    std::string database;
    std::string error;  ///< non-empty: training or evaluation failed
    std::size_t models = 0;
    std::size_t views = 0;       ///< views with a descriptor
    std::size_t signatures = 0;  ///< rows of the index (> views for cvfh, our-cvfh)
    double train_seconds = 0.0;  ///< this run's training (0 when the database was complete)
    EvaluationReport real;
    EvaluationReport synthetic;
};

using detail::seconds_since;

/// Descriptor names of a comma-separated list (CLI11 splits on the delimiter; entries may also
/// be repeated options), checked against the registry.
std::vector<std::string> checked_names(const std::vector<std::string>& requested) {
    const std::vector<std::string> valid = descriptor_names();
    if (requested.empty()) {  // every descriptor this build can compute
        std::vector<std::string> available;
        for (const auto& name : valid)
            if (descriptor_available(name)) available.push_back(name);
        return available;
    }
    std::vector<std::string> out;
    for (const auto& name : requested) {
        try {
            check_descriptor_name(name);
        } catch (const std::invalid_argument& e) {
            throw CLI::ValidationError("--descriptors", e.what());
        }
        require_descriptor(name);
        if (std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
    }
    return out;
}

void train_descriptor(const CompareArgs& args, CompareRow& row) {
    TrainingOptions options;
    options.render.level = args.level;
    options.descriptor = row.descriptor;
    options.seed = args.seed;
    options.threads = args.threads;
    std::optional<Progress> bar;
    std::size_t existing = 0;
    options.progress = [&](const TrainingProgress& p) {
        if (!bar) {
            existing = p.models_existing;
            bar.emplace("train " + row.descriptor, p.models_total - existing);
        }
        char detail[64];
        std::snprintf(detail, sizeof detail, "models, %zu views", p.views);
        bar->update(p.models_done - existing, detail);
    };
    const auto start = std::chrono::steady_clock::now();
    Database db(row.database, OpenMode::kWrite);
    const TrainingResult result = train(args.root, db, options);
    if (bar) bar->finish();
    if (result.models_trained + result.models_failed > 0) row.train_seconds = seconds_since(start);
    for (const auto& f : result.failures)
        std::fprintf(stderr, "esf: warning: %s: %s failed: %s\n", row.descriptor.c_str(),
                     f.model.c_str(), f.error.c_str());
}

EvaluationProgress progress_of(std::optional<Progress>& bar, const std::string& label) {
    return [&bar, label](std::size_t done, std::size_t total) {
        if (!bar) bar.emplace(label, total);
        bar->update(done, "queries");
    };
}

void evaluate_descriptor(const CompareArgs& args, const TestSet& test_set, CompareRow& row) {
    RecognizerOptions recognizer_options;
    recognizer_options.k = args.k;
    recognizer_options.descriptor = row.descriptor;
    recognizer_options.use_weights = false;  // plain L1 for every descriptor
    recognizer_options.verify = false;       // the descriptors compared, not the fit
    recognizer_options.threads = args.threads;
    const Recognizer recognizer(row.database, recognizer_options);
    row.models = recognizer.info().models;
    row.views = recognizer.info().views;
    row.signatures = recognizer.info().rows;
    {
        std::optional<Progress> bar;
        EvaluationOptions options;
        options.k = args.k;
        options.threads = args.threads;
        options.progress = progress_of(bar, "real " + row.descriptor);
        row.real = evaluate_test_set(recognizer, test_set, options);
        if (bar) bar->finish();
    }
    const DescriptorMatrix matrix = Database(row.database).load_descriptors(row.descriptor);
    std::optional<Progress> bar;
    SyntheticOptions options;
    options.k = args.k;
    options.threads = args.threads;
    options.max_queries = args.max_queries;
    if (!args.groups.empty()) options.groups = model_groups(matrix, read_catalog(args.groups));
    options.progress = progress_of(bar, "synthetic " + row.descriptor);
    row.synthetic = evaluate_synthetic(matrix, options);
    if (bar) bar->finish();
}

nlohmann::json report_json(const EvaluationReport& r) {
    return {{"samples", r.samples},
            {"top1", r.top1},
            {"topk", r.topk},
            {"class_top1", r.class_top1},
            {"class_topk", r.class_topk},
            {"skipped", r.skipped},
            {"failed", r.failed},
            {"describe_ms", r.describe_ms},
            {"match_ms", r.match_ms},
            {"seconds", r.total_seconds}};
}

void print_json(const CompareArgs& args, const std::vector<CompareRow>& rows) {
    nlohmann::json out = {
        {"root", args.root},
        {"test_set", args.test_set},
        {"work", args.work},
        {"k", args.k},
        {"view_sphere_level", args.level},
        {"synthetic", args.groups.empty() ? "leave-one-model-out" : "leave-one-group-out"}};
    out["descriptors"] = nlohmann::json::array();
    for (const auto& row : rows) {
        nlohmann::json r = {{"descriptor", row.descriptor}, {"database", row.database}};
        if (!row.error.empty()) {
            r["error"] = row.error;
        } else {
            r["models"] = row.models;
            r["views"] = row.views;
            r["signatures"] = row.signatures;
            r["train_seconds"] = row.train_seconds;
            r["real"] = report_json(row.real);
            r["synthetic"] = report_json(row.synthetic);
            r["ms_per_descriptor"] = row.real.describe_ms;
            r["ms_per_match"] = row.real.match_ms;
        }
        out["descriptors"].push_back(std::move(r));
    }
    std::cout << out.dump(2) << '\n';
}

void print_table(const CompareArgs& args, const std::vector<CompareRow>& rows) {
    const std::string k = std::to_string(args.k);
    const std::string real_k = "real " + k + "-NN", synthetic_k = "synth " + k + "-NN";
    std::printf("%-10s %10s %10s %10s %10s %9s %9s %8s\n", "descriptor", "real 1-NN",
                real_k.c_str(), "synth 1-NN", synthetic_k.c_str(), "ms/desc", "ms/match", "views");
    for (const auto& row : rows) {
        if (!row.error.empty()) {
            std::printf("%-10s %s\n", row.descriptor.c_str(), ("error: " + row.error).c_str());
            continue;
        }
        std::printf("%-10s %9.1f%% %9.1f%% %9.1f%% %9.1f%% %9.2f %9.3f %8zu\n",
                    row.descriptor.c_str(), 100.0 * row.real.top1, 100.0 * row.real.topk,
                    100.0 * row.synthetic.top1, 100.0 * row.synthetic.topk, row.real.describe_ms,
                    row.real.match_ms, row.views);
    }
    if (!rows.empty()) {
        const CompareRow* any = nullptr;
        for (const auto& row : rows)
            if (row.error.empty()) any = &row;
        if (any)
            std::printf(
                "real: %zu clouds of %s (%zu of classes not trained skipped, %zu failed); "
                "synthetic: %zu views, %s\n",
                any->real.samples, args.test_set.c_str(), any->real.skipped, any->real.failed,
                any->synthetic.samples,
                args.groups.empty() ? "leave-one-model-out" : "leave-one-group-out");
    }
}

void run_compare(const CompareArgs& args) {
    const std::vector<std::string> names = checked_names(args.descriptors);
    const TestSet test_set = read_test_set(args.test_set);
    std::filesystem::create_directories(args.work);
    std::vector<CompareRow> rows;
    bool failed = false;
    for (const auto& name : names) {
        CompareRow row;
        row.descriptor = name;
        row.database = (std::filesystem::path(args.work) / (name + ".sqlite")).string();
        try {
            train_descriptor(args, row);
            evaluate_descriptor(args, test_set, row);
        } catch (const std::exception& e) {
            row.error = e.what();
            failed = true;
            std::fprintf(stderr, "esf: error: %s: %s\n", name.c_str(), e.what());
        }
        rows.push_back(std::move(row));
    }
    if (args.json)
        print_json(args, rows);
    else
        print_table(args, rows);
    if (failed) throw ExitStatus{kExitRuntime};
}

}  // namespace

void add_compare_command(CLI::App& app) {
    auto args = std::make_shared<CompareArgs>();
    std::string names;
    for (const auto& n : descriptor_names()) names += (names.empty() ? "" : ",") + n;
    CLI::App* cmd = add_command(
        app, "compare", "Compare descriptors: train and evaluate each on identical data",
        "Compare descriptors on identical data: for each descriptor, train a database of ROOT in\n"
        "the work folder (DIR/<descriptor>.sqlite, resumed or reused when it exists; the same\n"
        "views, seeds and sensor noise for every descriptor), evaluate it on the labelled real\n"
        "clouds of TESTSET.csv (file,class) and leave-one-model-out on its own synthetic views\n"
        "(leave-one-group-out with --groups), and print one table: 1-NN and k-NN accuracy on\n"
        "both, and the mean time to describe one real cloud and to match one descriptor.\n"
        "Distances are plain L1 (no learned weights) for every descriptor.");
    cmd->add_option("root", args->root, "Folder of <category>/<model>.<ext> meshes")
        ->required()
        ->check(CLI::ExistingDirectory);
    cmd->add_option("test_set", args->test_set, "Test set CSV with columns file and class")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--descriptors", args->descriptors,
                    "Comma-separated descriptors (default: all of " + names + ")")
        ->delimiter(',');
    cmd->add_option("--work", args->work, "Folder of the databases (created)")
        ->capture_default_str();
    cmd->add_option("--level", args->level,
                    "View sphere subdivisions: 0 = 20, 1 = 80, 2 = 320 views")
        ->check(CLI::Range(0, 4))
        ->capture_default_str();
    cmd->add_option("-k", args->k,
                    "Nearest models per query, each by its nearest view (the k of k-NN)")
        ->check(CLI::Range(std::size_t{1}, std::size_t{1000}))
        ->capture_default_str();
    cmd->add_option("--groups", args->groups,
                    "Catalog CSV with shape groups: synthetic queries leave their whole group out")
        ->check(CLI::ExistingFile);
    cmd->add_option("--max-queries", args->max_queries,
                    "Synthetic queries: at most this many views, evenly spaced (0 = all)")
        ->capture_default_str();
    add_seed_option(*cmd, args->seed, "Training seed (sensor noise, descriptor sampling)");
    add_threads_option(*cmd, args->threads);
    cmd->add_flag("--json", args->json, "Print the comparison as one JSON object");
    cmd->callback([args] { run_compare(*args); });
}

}  // namespace esf::cli
