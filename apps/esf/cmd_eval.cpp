// esf eval DB TESTSET.csv | esf eval --synthetic DB : 1-NN and k-NN accuracy per sample and per
// class, the most confused class (the paper's Table I), and an optional report folder.

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "cli_evaluate.hpp"
#include "cli_recognize.hpp"
#include "cli_scene.hpp"
#include "commands.hpp"
#include "esf/evaluation/evaluation.hpp"
#include "esf/evaluation/scene_evaluation.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/report/report.hpp"
#include "esf/report/scene_report.hpp"
#include "esf/report/view_pictures.hpp"

namespace esf::cli {

namespace {

struct EvalArgs {
    std::string database;
    std::string test_set;
    std::size_t k = 10;
    std::string descriptor;
    bool no_weights = false;
    bool every_view = false;
    VoteRule vote = RecognizerOptions{}.vote;
    int samplings = 1;
    std::string queries;
    int threads = 0;
    bool synthetic = false;
    std::string groups;
    std::size_t max_queries = 0;
    std::string report;
    int gallery = -1;
    std::string meshes;
    RecognizerOptions verification;  // --no-verify, --verify-meshes, --candidates, ...
    std::string title;
    bool json = false;
    std::string scenes;
    SceneInputArgs scene_input;  // --scenes: the segmentation's options, as esf scene has them
};

std::string percent_of(std::size_t a, std::size_t b) {
    return b ? percent_text(static_cast<double>(a) / static_cast<double>(b)) : "-";
}

RecognizerOptions recognizer_options(const EvalArgs& args) {
    RecognizerOptions options;
    options.k = args.k;
    options.descriptor = args.descriptor;
    options.use_weights = !args.no_weights;
    options.one_view_per_model = !args.every_view;
    options.vote = args.vote;
    options.query_samplings = args.samplings;
    options.threads = args.threads;
    options.verify = args.verification.verify;
    options.verification_meshes = args.verification.verification_meshes;
    options.verification = args.verification.verification;
    options.merge_parts = args.verification.merge_parts;
    return options;
}

/// esf eval DB --scenes SCENES.csv
void run_scene_eval(const EvalArgs& args) {
    const SceneSet set = read_scene_set(args.scenes);
    const Recognizer recognizer(args.database, recognizer_options(args));
    if (!args.no_weights) warn_if_weights_stale(args.database, recognizer.info().setup.kind.name);
    warn_if_unverified(recognizer);
    SceneEvaluationOptions options;
    options.segmentation = segmentation_options(args.scene_input);
    options.segmentation.threads = args.threads;
    Progress progress("eval", set.scenes.size());
    options.progress = [&](std::size_t done, std::size_t) { progress.update(done); };
    SceneEvaluationReport report = evaluate_scenes(recognizer, set, options);
    report.database = args.database;
    progress.finish();
    for (const SceneFailure& f : report.failures)
        std::fprintf(stderr, "esf: warning: %s\n", with_file(f.file, f.error).c_str());

    if (!args.report.empty()) {
        const SceneReportFiles files = write_scene_report(
            args.report, report, args.title.empty() ? "esf eval: " + args.scenes : args.title);
        if (!args.json) std::printf("report: %s\n\n", files.html.c_str());
    }
    if (args.json) {
        std::cout << scene_report_json(report);
    } else {
        std::printf("scene set %s: %zu scenes, %zu objects\n\n", report.scene_set.c_str(),
                    set.scenes.size(), report.objects.size());
        std::printf("%-16s %7s %7s %6s %6s %6s %6s %9s %10s\n", "scene type", "objects", "found",
                    "split", "merged", "missed", "shared", "one-clust", "end-to-end");
        for (const SceneTypeSummary& t : report.types)
            std::printf("%-16s %7zu %7zu %6zu %6zu %6zu %6zu %8s%% %9s%%\n", t.type.c_str(),
                        t.objects, t.found, t.split, t.merged, t.missed, t.shared_clusters,
                        percent_of(t.found, t.objects).c_str(),
                        percent_of(t.correct, t.labelled).c_str());
        std::printf("\n%-16s %7s %7s %7s %9s %10s  %s\n", "class", "objects", "found", "named",
                    "one-clust", "end-to-end", "most often named instead");
        for (const SceneClassSummary& c : report.classes)
            std::printf(
                "%-16s %7zu %7zu %7zu %8s%% %9s%%  %s\n", c.class_name.c_str(), c.objects, c.found,
                c.correct, percent_of(c.found, c.objects).c_str(),
                percent_of(c.correct, c.objects).c_str(),
                c.confused_count
                    ? (c.confused_with + " (" + std::to_string(c.confused_count) + ")").c_str()
                    : "-");
        std::printf(
            "\nfound: one cluster holds >= 80 %% of the object and is >= 80 %% that object; "
            "shared: clusters holding parts of two or more objects; end-to-end: found and named "
            "right\nsegment %.2f ms, describe + classify %.2f ms per frame\n",
            report.segment_ms, report.recognize_ms);
        if (!report.truth.empty()) {
            std::printf(
                "\npose (truth.json; objects at least half visible whose model %s holds):\n",
                args.database.c_str());
            for (const SceneTypeSummary& t : report.types) {
                std::printf("%-16s %7zu judged, ADD-S < 0.1 d: %s%% (%s%% whatever model named)",
                            t.type.c_str(), t.posed, percent_of(t.pose_correct, t.posed).c_str(),
                            percent_of(t.pose_correct_any_model, t.posed).c_str());
                if (!t.rotation_errors.empty())
                    std::printf("; rotation error of %zu without symmetry: median %.1f deg",
                                t.rotation_errors.size(), t.rotation_median());
                std::printf("\n");
            }
        }
    }
    std::cout.flush();
    if (!std::cout) throw std::runtime_error("writing the output failed");
    if (report.objects.empty())
        throw std::invalid_argument("no scene could be evaluated (" +
                                    std::to_string(report.failures.size()) + " failed)");
}

void print_table(const EvaluationReport& r) {
    const std::string k = std::to_string(r.k) + "-NN";
    std::printf(
        "%s", (r.mode == "synthetic" ? "synthetic views, " + r.test_set : "test set " + r.test_set)
                  .c_str());
    std::printf(" (%s%s): %zu samples", r.descriptor.c_str(), r.weighted ? ", learned weights" : "",
                r.samples);
    if (r.skipped) {
        std::printf(", %zu skipped (not in the database:", r.skipped);
        for (const SkippedClass& s : r.missing_classes)
            std::printf(" %s %zu", s.class_name.c_str(), s.samples);
        std::printf(")");
    }
    if (r.failed) std::printf(", %zu failed", r.failed);
    std::printf("\n\n");
    std::printf("%-12s %7s %7s\n", "overall", "1-NN", k.c_str());
    std::printf("%-12s %6s%% %6s%%\n", "per sample", percent_text(r.top1).c_str(),
                percent_text(r.topk).c_str());
    std::printf("%-12s %6s%% %6s%%\n\n", "per class", percent_text(r.class_top1).c_str(),
                percent_text(r.class_topk).c_str());
    int width = 5;
    for (const ClassMetrics& c : r.classes)
        width = std::max(width, static_cast<int>(c.class_name.size()));
    std::printf("%-*s %7s %7s %7s  %s\n", width, "class", "samples", "1-NN", k.c_str(),
                "most confused with");
    for (const ClassMetrics& c : r.classes) {
        const std::string confused =
            c.confused_with.empty()
                ? "-"
                : c.confused_with + " (" + std::to_string(c.confused_count) + ")";
        std::printf("%-*s %7zu %6s%% %6s%%  %s\n", width, c.class_name.c_str(), c.samples,
                    percent_text(c.top1).c_str(), percent_text(c.topk).c_str(), confused.c_str());
    }
    std::printf("\n");
    if (r.describe_ms > 0.0) std::printf("describe %.2f ms per cloud, ", r.describe_ms);
    std::printf("match %.3f ms per query, %.2f s in all on %d threads\n", r.match_ms,
                r.total_seconds, r.threads);
}

void run_eval(const EvalArgs& args) {
    if (!args.scenes.empty()) {
        if (!args.test_set.empty() || args.synthetic)
            throw CLI::ValidationError("--scenes", "--scenes takes no TESTSET.csv or --synthetic");
        run_scene_eval(args);
        return;
    }
    if (!args.synthetic && args.test_set.empty())
        throw CLI::ValidationError(
            "eval", "a TESTSET.csv is needed (or --synthetic, or --scenes SCENES.csv)");
    if (args.synthetic && !args.test_set.empty())
        throw CLI::ValidationError("eval", "--synthetic takes no TESTSET.csv");
    if (!args.synthetic && !args.groups.empty())
        throw CLI::ValidationError("--groups", "--groups needs --synthetic");
    if (!args.synthetic && !args.queries.empty())
        throw CLI::ValidationError("--queries", "--queries needs --synthetic");
    if (!args.synthetic && args.max_queries)
        throw CLI::ValidationError("--max-queries", "--max-queries needs --synthetic");

    if (!args.meshes.empty() && (args.synthetic || args.report.empty()))
        throw CLI::ValidationError("--meshes", "--meshes needs a TESTSET.csv and --report DIR");
    EvaluationReport report;
    std::vector<GalleryEntry> gallery;
    if (args.synthetic) {
        const Database db(args.database, OpenMode::kRead);
        const DescriptorMatrix matrix = db.load_descriptors(args.descriptor);
        SyntheticOptions options;
        options.k = args.k;
        options.threads = args.threads;
        options.max_queries = args.max_queries;
        options.one_view_per_model = !args.every_view;
        options.groups = cli_model_groups(matrix, args.groups);
        if (!args.no_weights) {
            options.weights = stored_dimension_weights(db, matrix);
            warn_if_weights_stale(args.database, matrix.kind.name);
        }
        if (!args.queries.empty()) {
            const Database query_db(args.queries, OpenMode::kRead);
            const DescriptorMatrix queries = query_db.load_descriptors(matrix.kind.name);
            const std::vector<std::string> query_groups = cli_model_groups(queries, args.groups);
            Progress progress("eval", options.max_queries
                                          ? std::min(queries.rows(), options.max_queries)
                                          : queries.rows());
            options.progress = [&](std::size_t done, std::size_t) { progress.update(done); };
            report = evaluate_held_out(matrix, queries, query_groups, options);
            progress.finish();
            report.test_set = args.queries;
        } else {
            const std::size_t views = view_count(matrix);
            Progress progress("eval",
                              options.max_queries ? std::min(views, options.max_queries) : views);
            options.progress = [&](std::size_t done, std::size_t) { progress.update(done); };
            report = evaluate_synthetic(matrix, options);
            progress.finish();
        }
        report.database = args.database;
    } else {
        const TestSet set = read_test_set(args.test_set);
        const Recognizer recognizer(args.database, recognizer_options(args));
        if (!args.no_weights)
            warn_if_weights_stale(args.database, recognizer.info().setup.kind.name);
        warn_if_unverified(recognizer);
        EvaluationOptions options;
        options.k = args.k;
        options.threads = args.threads;
        const std::vector<std::string>& categories = recognizer.info().categories;
        const auto evaluated = static_cast<std::size_t>(
            std::count_if(set.samples.begin(), set.samples.end(), [&](const TestSample& t) {
                return std::find(categories.begin(), categories.end(), t.class_name) !=
                       categories.end();
            }));
        Progress progress("eval", evaluated);
        options.progress = [&](std::size_t done, std::size_t) { progress.update(done); };
        report = evaluate_test_set(recognizer, set, options);
        progress.finish();
        for (const QueryFailure& f : report.failures)
            std::fprintf(stderr, "esf: warning: %s\n", with_file(f.file, f.error).c_str());
        if (!args.report.empty() && args.gallery != 0) {
            std::unique_ptr<ViewRenderer> views;
            if (!args.meshes.empty())
                views = std::make_unique<ViewRenderer>(args.database, args.meshes);
            GalleryOptions gallery_options;
            gallery_options.per_class =
                args.gallery < 0 ? 0 : static_cast<std::size_t>(args.gallery);
            gallery_options.views = views.get();
            gallery = misclassified_gallery(recognizer, report, gallery_options);
        }
    }

    if (!args.report.empty()) {
        ReportOptions options;
        options.title = args.title.empty() ? "esf eval: " + args.database : args.title;
        options.gallery = std::move(gallery);
        const ReportFiles files = write_report(args.report, report, options);
        if (!args.json) std::printf("report: %s\n", files.html.c_str());
    }
    if (args.json) {
        ReportOptions options;
        options.include_queries = false;
        options.title = args.title;
        std::cout << report_json(report, options);
    } else {
        if (!args.report.empty()) std::printf("\n");
        print_table(report);
    }
    std::cout.flush();
    if (!std::cout) throw std::runtime_error("writing the output failed");
    if (report.samples == 0)
        throw std::invalid_argument("no sample could be evaluated (" +
                                    std::to_string(report.skipped) + " skipped, " +
                                    std::to_string(report.failed) + " failed)");
}

}  // namespace

void add_eval_command(CLI::App& app) {
    auto args = std::make_shared<EvalArgs>();
    CLI::App* cmd = add_command(
        app, "eval", "Measure accuracy on a test set, synthetic views or labelled scenes",
        "Measure classification accuracy (Wohlkinger & Vincze 2011, Table I).\n"
        "  esf eval DB TESTSET.csv     labelled real clouds: a CSV with a header naming at least\n"
        "                              the columns file and class (paths relative to the CSV)\n"
        "  esf eval --synthetic DB     the database's own views, leave-one-model-out: each\n"
        "                              model's views against all other models' views (with\n"
        "                              --groups, all models of the same group are left out)\n"
        "  esf eval DB --scenes S.csv  whole labelled scenes, segmented and recognised as by\n"
        "                              esf scene: S.csv has the columns scene_file (an\n"
        "                              organised PCD with a per-point label field, label / 10 =\n"
        "                              object id), object_id, class and optionally scene_type.\n"
        "                              Per object: found (one cluster holds >= 80 % of it and\n"
        "                              is >= 80 % it), split, merged or missed; end-to-end:\n"
        "                              found and named right; per scene type and overall;\n"
        "                              --report DIR writes scenes.json and index.html\n"
        "Each cloud is described with the database's descriptor and settings and its k nearest\n"
        "views are found (L1, with the learned weights when stored). 1-NN: the nearest view has\n"
        "the true class; k-NN: the true class is among the k nearest views' classes. Printed per\n"
        "sample and per class (the mean of the class accuracies), then per class with the most\n"
        "confused class. Rows whose class is not in the database are skipped and counted; clouds\n"
        "that cannot be read or described are reported on stderr and counted as failed.\n"
        "--json prints one object: {overall: {samples, top1, top10, class_top1, class_top10,\n"
        "rank_curve, ...}, classes: [{class, samples, top1, top10, confused_with, ...}],\n"
        "confusion, skipped, missing_classes, failed, failures, timings}, fractions in [0, 1];\n"
        "top10 and class_top10 hold the top-k values for any -k. --report DIR writes\n"
        "report.json, confusion.png (cells only) and .svg (with labels), rank_curves.svg and a\n"
        "self-contained index.html; for a test set the page also shows the misclassified\n"
        "queries (--gallery N: the first N per class), each drawn next to the training view it\n"
        "was matched to and the nearest view of its true class (drawn from the meshes given\n"
        "by --meshes ROOT, the folder DB was trained from).\n"
        "Exit status 2 when no sample could be evaluated.");
    cmd->add_option("database", args->database, "Training database (esf train ... -o DB)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("testset", args->test_set,
                    "Test set CSV with file and class columns (not with --synthetic)")
        ->check(CLI::ExistingFile);
    cmd->add_option("-k", args->k,
                    "Nearest models per query (each by its nearest view) for the k-NN accuracy "
                    "and rank curve")
        ->check(CLI::Range(1, 1000))
        ->capture_default_str();
    cmd->add_option("--descriptor", args->descriptor,
                    "Descriptor kind to evaluate when the database holds several");
    cmd->add_flag("--no-weights", args->no_weights,
                  "Ignore the database's learned sub-histogram weights (plain L1)");
    cmd->add_flag("--every-view", args->every_view,
                  "Rank the k nearest views, several of one model among them (the paper's "
                  "ranks; default: one view per model)");
    add_enum_option(*cmd, "--vote", args->vote,
                    "Scenes: how the neighbours name an object's class, nearest or majority");
    cmd->add_option("--samplings", args->samplings,
                    "Describe each query this many times (other seeds) and average")
        ->check(CLI::Range(1, 64))
        ->capture_default_str();
    add_threads_option(*cmd, args->threads);
    cmd->add_flag("--synthetic", args->synthetic,
                  "Leave-one-model-out over the database's own views instead of a test set");
    cmd->add_option("--groups", args->groups,
                    "With --synthetic: catalog CSV (file, group columns); all views of a query's "
                    "group are left out")
        ->check(CLI::ExistingFile);
    cmd->add_option("--queries", args->queries,
                    "With --synthetic: take the views of this database as queries (held out: "
                    "the views of their group are left out of DB)")
        ->check(CLI::ExistingFile);
    cmd->add_option("--max-queries", args->max_queries,
                    "With --synthetic: query at most N evenly spaced views (0 = all)")
        ->capture_default_str();
    cmd->add_option("--report", args->report,
                    "Write report.json, confusion.png/.svg, rank_curves.svg, index.html to DIR");
    cmd->add_option("--gallery", args->gallery,
                    "With --report and a test set: misclassified queries shown per class "
                    "(-1 = all, 0 = none)")
        ->check(CLI::Range(-1, 1000000))
        ->capture_default_str();
    cmd->add_option("--meshes", args->meshes,
                    "With --report: the training root DB was trained from; the gallery draws "
                    "training views from its meshes")
        ->check(CLI::ExistingDirectory);
    add_verification_options(*cmd, args->verification);
    cmd->add_option("--scenes", args->scenes,
                    "Evaluate segmentation and recognition on labelled scenes (CSV: scene_file, "
                    "object_id, class[, scene_type])")
        ->check(CLI::ExistingFile);
    add_segmentation_options(*cmd, args->scene_input);
    cmd->add_option("--title", args->title, "Title of the report (default: esf eval: DB)");
    cmd->add_flag("--json", args->json, "Print one JSON object instead of the tables");
    cmd->callback([args] { run_eval(*args); });
}

}  // namespace esf::cli
