// esf demo: the main job end to end on generated models, offline, with nothing to download:
// generate training models, train a database, classify held-out models (Table I), and
// recognise the objects of a synthetic table scene.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "commands.hpp"
#include "core/atomic_file.hpp"
#include "core/number_text.hpp"
#include "esf/demo/demo.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/io/depth_image.hpp"
#include "esf/render/view_sphere.hpp"
#include "esf/report/report.hpp"
#include "esf/report/scene_page.hpp"

namespace esf::cli {

namespace {

struct DemoArgs {
    DemoOptions options;
    std::string report;
    bool json = false;
};

nlohmann::json vec(const Eigen::Vector3f& v) {
    auto number = [](float x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(); };
    return {number(v.x()), number(v.y()), number(v.z())};
}

double per_second(std::size_t count, double seconds) {
    return seconds > 0.0 ? static_cast<double>(count) / seconds : 0.0;
}

/// "12.3%" for a share 0.123.
std::string percent(double share) { return detail::percent_text(share) + "%"; }

const char* object_status(const RecognizedObject& o) {
    return o.classified() ? to_string(o.cluster.status) : "failed";
}

nlohmann::json demo_json(const DemoResult& r) {
    const EvaluationReport& e = r.evaluation;
    nlohmann::json out;
    out["seed"] = r.seed;
    out["categories"] = r.categories;
    out["work_dir"] = r.work_dir;
    out["work_dir_removed"] = r.work_dir_removed;
    out["database"] = r.database;
    out["training"] = {{"models", r.train_models},
                       {"models_existing", r.train_models_existing},
                       {"per_class", r.per_class},
                       {"level", r.level},
                       {"views_per_model", view_count(r.level)},
                       {"views", r.train_views},
                       {"views_skipped", r.train_views_skipped},
                       {"database_views", r.database_views},
                       {"seconds", r.seconds.train},
                       {"views_per_second", per_second(r.train_views, r.seconds.train)}};
    out["queries"] = {{"models_per_class", r.query_models},
                      {"views_per_model", r.query_views},
                      {"views", r.queries.size()},
                      {"evaluated", e.samples},
                      {"failed", e.failed},
                      {"k", e.k},
                      {"top1", e.top1},
                      {"top10", e.topk},
                      {"class_top1", e.class_top1},
                      {"class_top10", e.class_topk},
                      {"seconds", r.seconds.query}};
    out["table"] = nlohmann::json::array();
    for (const ClassMetrics& m : e.classes)
        out["table"].push_back({{"class", m.class_name},
                                {"views", m.samples},
                                {"failed", m.failed},
                                {"top1", m.top1},
                                {"top10", m.topk},
                                {"confused_with", m.confused_with},
                                {"confused_count", m.confused_count}});
    out["confusion"] = {
        {"rows", e.confusion_rows}, {"columns", e.confusion_columns}, {"counts", e.confusion}};

    const DemoScene& s = r.scene;
    nlohmann::json scene;
    scene["placed"] = nlohmann::json::array();
    for (const DemoPlacedObject& p : s.placed)
        scene["placed"].push_back(
            {{"class", p.category},
             {"model", p.model},
             {"position", vec(p.position)},
             {"yaw_deg", p.yaw_deg},
             {"extent", vec(p.extent)},
             {"visible_points", p.visible_points},
             {"visible_centroid", vec(p.visible_centroid)},
             {"found_as", p.found_as < 0 ? nlohmann::json() : nlohmann::json(p.found_as)}});
    scene["plane_found"] = s.recognition.plane_found;
    scene["plane"] = {{"normal", vec(s.recognition.plane.normal)},
                      {"d", s.recognition.plane.d},
                      {"inliers", s.recognition.plane_inliers}};
    scene["message"] = s.recognition.message;
    scene["objects"] = nlohmann::json::array();
    for (std::size_t i = 0; i < s.recognition.objects.size(); ++i) {
        const RecognizedObject& o = s.recognition.objects[i];
        const DemoFoundObject& f = s.found[i];
        nlohmann::json entry;
        entry["class"] = o.classified() ? nlohmann::json(o.classification.class_name) : nullptr;
        entry["confidence"] = o.classified() ? o.classification.confidence : 0.0;
        entry["model"] = o.classification.best_model;
        entry["centroid"] = vec(o.cluster.centroid);
        entry["size"] = vec(o.cluster.size);
        entry["points"] = o.cluster.points.size();
        entry["status"] = object_status(o);
        entry["message"] = o.error.empty() ? o.cluster.message : o.error;
        entry["placed"] = f.placed < 0 ? nlohmann::json() : nlohmann::json(f.placed);
        entry["true_class"] = f.placed < 0
                                  ? nlohmann::json()
                                  : nlohmann::json(s.placed[std::size_t(f.placed)].category);
        entry["label_share"] = f.label_share;
        entry["correct"] = f.correct;
        scene["objects"].push_back(std::move(entry));
    }
    scene["found"] = s.found_placed;
    scene["correct"] = s.correct;
    scene["seconds"] = r.seconds.scene;
    out["scene"] = std::move(scene);
    out["seconds"] = {{"generate", r.seconds.generate},
                      {"train", r.seconds.train},
                      {"query", r.seconds.query},
                      {"scene", r.seconds.scene},
                      {"total", r.seconds.total}};
    return out;
}

void print_table(const DemoResult& r) {
    const EvaluationReport& e = r.evaluation;
    std::printf("\nTable I: held-out models (none of them in the database), %zu views\n",
                e.samples);
    std::printf("  %-14s %6s %7s %7s   %s\n", "class", "views", "1-NN", "10-NN",
                "most confused with (1-NN)");
    for (const ClassMetrics& m : e.classes) {
        std::string confused = m.confused_with.empty() ? std::string("-")
                                                       : m.confused_with + " (" +
                                                             std::to_string(m.confused_count) + ")";
        if (m.failed) confused += ", " + std::to_string(m.failed) + " failed";
        std::printf("  %-14s %6zu %7s %7s   %s\n", m.class_name.c_str(), m.samples,
                    percent(m.top1).c_str(), percent(m.topk).c_str(), confused.c_str());
    }
    std::printf("  %-14s %6zu %7s %7s   (per view; class mean %s / %s)\n", "all", e.samples,
                percent(e.top1).c_str(), percent(e.topk).c_str(), percent(e.class_top1).c_str(),
                percent(e.class_topk).c_str());
    if (e.failed) std::printf("  %zu views could not be described\n", e.failed);
}

void print_scene(const DemoOptions& options, const DemoResult& r) {
    const DemoScene& s = r.scene;
    if (s.placed.empty()) return;
    std::printf(
        "\n[4/4] scene: %zu held-out models on a table, Kinect %.1f m away looking down at "
        "%.0f deg; segment, then classify each object (%.1f s)\n",
        s.placed.size(), options.scene_distance, options.scene_elevation_deg, r.seconds.scene);
    std::printf("  placed:");
    for (std::size_t i = 0; i < s.placed.size(); ++i)
        std::printf("%s %s", i ? "," : "", s.placed[i].category.c_str());
    std::printf("\n  segmentation: %s (plane of %zu points; centroids in the camera frame)\n",
                s.recognition.message.c_str(), s.recognition.plane_inliers);
    if (!s.recognition.objects.empty()) {
        std::printf("  %2s  %-13s %4s %7s  %-20s   %-17s    %s\n", "#", "class", "conf", "points",
                    "centroid x y z (m)", "length width height", "true object");
        for (std::size_t i = 0; i < s.recognition.objects.size(); ++i) {
            const RecognizedObject& o = s.recognition.objects[i];
            const DemoFoundObject& f = s.found[i];
            const Cluster& c = o.cluster;
            const std::string truth =
                f.placed < 0 ? "(table)" : s.placed[std::size_t(f.placed)].category;
            const char* verdict = f.placed < 0 ? "" : (f.correct ? "recognised" : "WRONG");
            std::printf(
                "  %2zu  %-13s %4.2f %7zu  %6.3f %6.3f %6.3f   %5.3f %5.3f %5.3f    %-13s  %s", i,
                o.classified() ? o.classification.class_name.c_str() : "-",
                o.classified() ? o.classification.confidence : 0.0, c.points.size(), c.centroid.x(),
                c.centroid.y(), c.centroid.z(), c.size.x(), c.size.y(), c.size.z(), truth.c_str(),
                verdict);
            if (!o.classified()) std::printf(" (%s)", o.error.c_str());
            if (c.status != ClusterStatus::kOk) std::printf(" (%s)", c.message.c_str());
            std::printf("\n");
        }
    }
    for (const DemoPlacedObject& p : s.placed)
        if (p.found_as < 0)
            std::printf("  not found: %s (%zu pixels visible)\n", p.category.c_str(),
                        p.visible_points);
    std::printf("  %zu of %zu placed objects found, %zu of them classified correctly\n",
                s.found_placed, s.placed.size(), s.correct);
}

/// Prints each stage as it starts and ends, with a progress bar on a terminal.
class StagePrinter {
  public:
    StagePrinter(const DemoOptions& o, bool quiet) : options_(o), quiet_(quiet) {}

    void operator()(const DemoProgress& p) {
        if (!started_ || p.stage != stage_) start(p);
        if (bar_) bar_->update(p.done);
        if (p.done >= p.total && !ended_) end(p);
    }

  private:
    void start(const DemoProgress& p) {
        started_ = true;
        stage_ = p.stage;
        ended_ = false;
        if (!quiet_) {
            const std::size_t categories = 10;
            const std::size_t train = categories * std::size_t(options_.per_class);
            const std::size_t held_out = categories * std::size_t(options_.query_models);
            switch (p.stage) {
                case DemoStage::kGenerate:
                    std::printf("[1/4] generating %zu training models (%d per category)\n", train,
                                options_.per_class);
                    break;
                case DemoStage::kTrain:
                    std::printf(
                        "[2/4] training: %zu models x %zu views (view sphere level %d), Kinect "
                        "noise, ESF per view\n",
                        train, view_count(options_.level), options_.level);
                    break;
                case DemoStage::kQuery:
                    std::printf(
                        "[3/4] querying: %zu held-out models (%d per category) x %d random views, "
                        "Kinect noise, 10 nearest views each\n",
                        held_out, options_.query_models, options_.query_views);
                    break;
                case DemoStage::kScene:
                    break;
            }
            std::fflush(stdout);
        }
        if (p.stage != DemoStage::kScene)  // one short step: no bar
            bar_ = std::make_unique<Progress>(std::string("  ") + to_string(p.stage), p.total);
    }

    void end(const DemoProgress& p) {
        ended_ = true;
        if (bar_) bar_->finish();
        bar_.reset();
        if (quiet_) return;
        if (p.stage == DemoStage::kTrain && p.views == 0)
            std::printf("      all %zu models already in the database (--work), none retrained\n",
                        p.total);
        else if (p.stage == DemoStage::kTrain)
            std::printf("      %zu views described in %.1f s (%.0f views/s)\n", p.views, p.seconds,
                        per_second(p.views, p.seconds));
        else if (p.stage != DemoStage::kScene)
            std::printf("      done in %.1f s\n", p.seconds);
        std::fflush(stdout);
    }

    const DemoOptions& options_;
    bool quiet_;
    std::unique_ptr<Progress> bar_;
    bool started_ = false;
    DemoStage stage_ = DemoStage::kGenerate;
    bool ended_ = false;
};

void write_demo_report(const std::string& dir, const DemoResult& r, const nlohmann::json& json) {
    namespace fs = std::filesystem;
    ReportOptions options;
    options.title = "esf demo: held-out generated models";
    write_report(dir, r.evaluation, options);  // creates the folder
    const fs::path root(dir);
    detail::write_file_atomically(root / "demo.json", json.dump(2) + '\n');
    if (r.scene.cloud.points.empty()) return;
    write_pcd((root / "scene.pcd").string(), r.scene.cloud);
    DepthImage depth;
    depth.width = r.scene.cloud.width;
    depth.height = r.scene.cloud.height;
    depth.depth.reserve(r.scene.cloud.points.size());
    for (const Eigen::Vector3f& p : r.scene.cloud.points)
        depth.depth.push_back(std::isfinite(p.z()) && p.z() > 0.0f && p.z() < 65.0f
                                  ? static_cast<std::uint16_t>(std::lround(p.z() * 1000.0f))
                                  : std::uint16_t{0});
    write_depth_png((root / "scene_depth.png").string(), depth);
    ScenePageOptions page;
    page.title = "esf demo scene";
    write_page(dir, "scene.html",
               scene_page_html("generated scene", r.scene.cloud, r.scene.recognition, {}, page));
}

void run_demo_command(const DemoArgs& args) {
    DemoOptions options = args.options;
    StagePrinter printer(options, args.json);
    options.progress = [&printer](const DemoProgress& p) { printer(p); };
    if (!args.json) {
        std::printf(
            "esf demo (seed %llu): train on generated models of the paper's 10 categories, then "
            "classify held-out ones\n",
            static_cast<unsigned long long>(options.seed));
        std::printf("  work folder: %s\n", options.work_dir.empty()
                                               ? "a temporary folder, removed at the end"
                                               : options.work_dir.c_str());
        std::fflush(stdout);
    }
    const DemoResult r = run_demo(options);
    const nlohmann::json json = demo_json(r);
    if (!args.report.empty()) write_demo_report(args.report, r, json);
    if (args.json) {
        std::cout << json.dump(2) << '\n';
    } else {
        print_table(r);
        print_scene(options, r);
        std::printf("\ntotal %.1f s (generate %.1f, train %.1f, query %.1f, scene %.1f)\n",
                    r.seconds.total, r.seconds.generate, r.seconds.train, r.seconds.query,
                    r.seconds.scene);
        if (!args.report.empty())
            std::printf(
                "report: %s/index.html (report.json, demo.json, scene.html, scene.pcd, "
                "scene_depth.png)\n",
                args.report.c_str());
    }
    std::cout.flush();
    if (std::fflush(stdout) != 0 || !std::cout)
        throw std::runtime_error("writing the output failed");
}

}  // namespace

void add_demo_command(CLI::App& app) {
    auto args = std::make_shared<DemoArgs>();
    DemoOptions& o = args->options;
    CLI::App* cmd = add_command(
        app, "demo", "Run the whole job offline on generated models, then a table scene",
        "Run the main job end to end on generated models, offline: generate training meshes of\n"
        "the paper's 10 categories (esf generate), train a database from their views with the\n"
        "Kinect sensor model (esf train), classify views of HELD-OUT models that are not in the\n"
        "database and print the paper's Table I (per class 1-NN and 10-NN accuracy, most\n"
        "confused class), then compose a table scene of held-out objects, segment it and\n"
        "classify every object (esf scene), saying for each whether it was recognised.\n"
        "Everything follows from --seed. With --work DIR the models and the database stay in\n"
        "DIR, and a second run reuses the database. --json prints {seed, categories, work_dir,\n"
        "database, training, queries, table: [{class, views, failed, top1, top10, confused_with,\n"
        "confused_count}], confusion, scene: {placed, plane_found, plane, message, objects:\n"
        "[{class, confidence, model, centroid, size, points, status, message, placed,\n"
        "true_class, label_share, correct}], found, correct}, seconds}. With --work and\n"
        "--report, `esf scene WORK/demo_*.db REPORT/scene_depth.png` recognises the scene again.");
    add_seed_option(*cmd, o.seed, "Random seed of models, views, noise and scene");
    cmd->add_option("--per-class", o.per_class, "Training models per category")
        ->capture_default_str()
        ->check(CLI::Range(1, 1000));
    cmd->add_option("--level", o.level, "Training view sphere: 0 = 20 views, 1 = 80, 2 = 320")
        ->capture_default_str()
        ->check(CLI::Range(0, 3));
    cmd->add_option("--query-models", o.query_models, "Held-out models per category")
        ->capture_default_str()
        ->check(CLI::Range(1, 1000));
    cmd->add_option("--query-views", o.query_views, "Random views per held-out model")
        ->capture_default_str()
        ->check(CLI::Range(1, 10000));
    cmd->add_option("--scene-objects", o.scene_objects, "Objects on the table (0 = no scene)")
        ->capture_default_str()
        ->check(CLI::Range(0, 10));
    cmd->add_option("--report", args->report,
                    "Write DIR/index.html, report.json, confusion.png/svg, rank_curves.svg (the "
                    "held-out evaluation), demo.json (as --json), scene.html (the scene's page: "
                    "frame, outlined objects, classes), scene.pcd (labelled) and "
                    "scene_depth.png (16-bit, mm)");
    cmd->add_option("--work", o.work_dir,
                    "Keep the generated models and the database in this folder (default: a "
                    "temporary folder, removed at the end)");
    cmd->add_flag("--json", args->json, "Print one JSON object instead of the text");
    add_threads_option(*cmd, o.threads);
    cmd->callback([args] { run_demo_command(*args); });
}

}  // namespace esf::cli
