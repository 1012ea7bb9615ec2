// esf scene DB SCENE... : segment table scenes and classify every object on the table.

#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "cli_recognize.hpp"
#include "cli_scene.hpp"
#include "commands.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/report/scene_page.hpp"
#include "esf/report/view_pictures.hpp"
#include "esf/segmentation/segmentation.hpp"

namespace esf::cli {

namespace {

struct SceneArgs {
    RecognizerArgs recognizer;
    SceneInputArgs input;
    std::vector<std::string> scenes;
    bool json = false;
    std::string report;
    std::string meshes;
};

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

nlohmann::json vec(const Eigen::Vector3f& v) { return {v.x(), v.y(), v.z()}; }

const char* object_status(const RecognizedObject& o) {
    if (!o.classified()) return "failed";
    return to_string(o.cluster.status);
}

/// The object's messages: why it has no class, and whether it may be cut off.
std::string object_message(const RecognizedObject& o) {
    std::string message = o.error;
    if (!o.cluster.message.empty()) message += (message.empty() ? "" : "; ") + o.cluster.message;
    return message;
}

nlohmann::json scene_json(const std::string& file, const SceneRecognition& scene, double segment_ms,
                          double recognise_ms) {
    nlohmann::json out;
    out["file"] = file;
    out["plane_found"] = scene.plane_found;
    out["plane"] = {{"normal", vec(scene.plane.normal)},
                    {"d", scene.plane.d},
                    {"inliers", scene.plane_inliers}};
    out["message"] = scene.message;
    out["time_ms"] = {{"segment", segment_ms}, {"recognise", recognise_ms}};
    out["objects"] = nlohmann::json::array();
    for (const RecognizedObject& o : scene.objects) {
        nlohmann::json entry;
        if (o.classified()) {
            add_classification_json(entry, o.classification);
        } else {
            entry["class"] = nullptr;
            entry["confidence"] = 0.0;
            entry["neighbours"] = nlohmann::json::array();
        }
        entry["centroid"] = vec(o.cluster.centroid);
        entry["size"] = vec(o.cluster.size);
        entry["points"] = o.cluster.points.size();
        entry["status"] = object_status(o);
        entry["message"] = object_message(o);
        out["objects"].push_back(std::move(entry));
    }
    return out;
}

void print_scene(const std::string& file, const SceneRecognition& scene, double segment_ms,
                 double recognise_ms) {
    std::printf("%s: %s (segment %.1f ms, describe + classify %.1f ms)\n", file.c_str(),
                scene.message.c_str(), segment_ms, recognise_ms);
    if (scene.objects.empty()) return;
    std::size_t class_width = 5, model_width = 5;
    for (const RecognizedObject& o : scene.objects) {
        if (!o.classified()) continue;
        class_width = std::max(class_width, o.classification.class_name.size());
        model_width = std::max(model_width, o.classification.best_model.size());
    }
    const int cw = static_cast<int>(class_width), mw = static_cast<int>(model_width);
    std::printf("  %2s  %-*s  %4s  %-*s  %4s  %8s  %7s  %-23s  %-20s  %s\n", "#", cw, "class",
                "conf", mw, "model", "view", "distance", "points", "centroid x y z (m)",
                "length width height", "status");
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const RecognizedObject& o = scene.objects[i];
        const Cluster& c = o.cluster;
        const Classification& k = o.classification;
        const std::string message = object_message(o);
        if (o.classified())
            std::printf("  %2zu  %-*s  %4.2f  %-*s  %4d  %8.4f", i, cw, k.class_name.c_str(),
                        k.confidence, mw, k.best_model.c_str(), k.best_view, k.best_distance);
        else
            std::printf("  %2zu  %-*s  %4s  %-*s  %4s  %8s", i, cw, "-", "-", mw, "-", "-", "-");
        std::printf("  %7zu  %7.3f %7.3f %7.3f  %6.3f %6.3f %6.3f  %s%s%s\n", c.points.size(),
                    c.centroid.x(), c.centroid.y(), c.centroid.z(), c.size.x(), c.size.y(),
                    c.size.z(), object_status(o), message.empty() ? "" : ": ",
                    (message + (o.classified() ? fit_text(k) : std::string())).c_str());
    }
}

/// "scene_007_mosd_learn0.html": the scene's number and its file name, letters, digits, '-'
/// and '_' only.
std::string page_name(std::size_t index, const std::string& file) {
    std::string stem = std::filesystem::path(file).stem().string();
    for (char& c : stem)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
    char number[16];
    std::snprintf(number, sizeof number, "%03zu", index);
    return "scene_" + std::string(number) + "_" + stem + ".html";
}

/// The nearest training view of each classified object, drawn from its mesh when the meshes
/// are known; otherwise the fitted model's stored surface where verification placed it.
std::vector<MatchedView> matched_views(const SceneRecognition& scene, ViewRenderer* views,
                                       const Recognizer& recognizer) {
    std::vector<MatchedView> out(scene.objects.size());
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const RecognizedObject& o = scene.objects[i];
        if (!o.classified()) continue;
        if (!views) {
            try {
                out[i].points = recognizer.posed_surface(o.classification);
                out[i].posed = !out[i].points.empty();
            } catch (const std::exception& e) {
                out[i].note = e.what();
                continue;
            }
            if (!out[i].posed) out[i].note = "training views are drawn with --meshes ROOT";
            continue;
        }
        try {
            const Classification& c = o.classification;
            out[i].points = views->render(c.class_name, c.best_model, c.pose);
            // Verified: the pose places the model on the object, in the scene's camera frame.
            out[i].posed = c.fit.has_value();
            if (out[i].points.empty()) out[i].note = "the view has no points";
        } catch (const std::exception& e) {
            out[i].note = e.what();
        }
    }
    return out;
}

void run_scene(SceneArgs& args) {
    if (!args.meshes.empty() && args.report.empty())
        throw CLI::ValidationError("--meshes", "--meshes needs --report DIR");
    SegmentationOptions segmentation = segmentation_options(args.input);
    segmentation.threads = args.recognizer.options.threads;
    const Recognizer recognizer(args.recognizer.database, recognizer_options(args.recognizer));
    if (!args.recognizer.no_weights)
        warn_if_weights_stale(args.recognizer.database, recognizer.info().setup.kind.name);
    warn_if_unverified(recognizer);

    std::unique_ptr<ViewRenderer> views;
    if (!args.meshes.empty())
        views = std::make_unique<ViewRenderer>(args.recognizer.database, args.meshes);
    std::vector<ScenePageLink> links;
    ScenePageOptions page_options;
    page_options.plane_distance = segmentation.plane_distance;

    int failed = 0;
    nlohmann::json all = nlohmann::json::array();
    for (const std::string& file : args.scenes) {
        ScenePageLink link;
        link.file = file;
        try {
            const PointCloud cloud = load_scene_cloud(file, args.input);
            auto start = Clock::now();
            SegmentationResult segments = segment_scene(cloud, segmentation);
            const double segment_ms = ms_since(start);
            start = Clock::now();
            const SceneRecognition scene = recognizer.recognize(std::move(segments), cloud);
            const double recognise_ms = ms_since(start);
            if (args.json)
                all.push_back(scene_json(file, scene, segment_ms, recognise_ms));
            else
                print_scene(file, scene, segment_ms, recognise_ms);
            if (!args.report.empty()) {
                const std::vector<MatchedView> matched =
                    matched_views(scene, views.get(), recognizer);
                const std::string name = page_name(links.size(), file);
                write_page(args.report, name,
                           scene_page_html(file, cloud, scene, matched, page_options));
                link.page = name;
                link.message = scene.message;
                for (const RecognizedObject& o : scene.objects)
                    link.classes.push_back(o.classified() ? o.classification.class_name : "-");
            }
        } catch (const std::exception& e) {
            std::fprintf(stderr, "esf: error: %s\n", with_file(file, e.what()).c_str());
            link.error = e.what();
            ++failed;
        }
        links.push_back(std::move(link));
        std::fflush(stdout);
    }
    if (!args.report.empty()) {
        const std::string index =
            write_page(args.report, "index.html", scene_index_html(links, "esf scene"));
        if (!args.json) std::printf("report: %s\n", index.c_str());
    }
    if (args.json)
        std::cout << (args.scenes.size() == 1 && all.size() == 1 ? all[0] : all).dump(2) << '\n';
    std::cout.flush();
    if (!std::cout) throw std::runtime_error("writing the output failed");
    if (failed) throw ExitStatus{kExitRuntime};
}

}  // namespace

void add_scene_command(CLI::App& app) {
    auto args = std::make_shared<SceneArgs>();
    CLI::App* cmd = add_command(
        app, "scene", "Recognise the objects on a table: segment, then classify each",
        "Each scene is segmented as by esf segment (the dominant plane, and the objects above\n"
        "it grouped by --grouping, convexity by default), every object is described with the\n"
        "database's descriptor and settings (in parallel) and classified by its k nearest\n"
        "views. The\n"
        "database is loaded once for all scenes. Prints per object its class, confidence,\n"
        "nearest model, view and distance, points, centroid and size (metres), and status\n"
        "(ok, maybe_truncated, or failed with the reason). --json prints per scene {file,\n"
        "plane_found, plane, message, time_ms, objects: [{class, confidence, model, view,\n"
        "distance, pose, centroid, size, points, status, message, neighbours}]} (an array for\n"
        "several scenes; poses model -> camera, 16 numbers row-major; size = length, width,\n"
        "height). A scene that cannot be read is reported on stderr, the others go on, and the\n"
        "exit status is then 2; a scene without plane or objects says so. --report DIR writes\n"
        "a self-contained page per scene and DIR/index.html linking them: the frame shaded by\n"
        "depth with the table in green and every object outlined and labelled, then each object\n"
        "drawn next to its nearest training view (drawn from the meshes under --meshes ROOT,\n"
        "the folder DB was trained from).");
    add_recognizer_options(*cmd, args->recognizer);
    cmd->add_option("scenes", args->scenes,
                    "Scenes: point clouds (.pcd, .ply, .xyz), organised or not, or 16-bit depth "
                    "PNGs")
        ->required();
    cmd->add_flag("--json", args->json, "Print JSON instead of the tables");
    cmd->add_option("--report", args->report,
                    "Write a page per scene and index.html into DIR (created when missing)");
    cmd->add_option("--meshes", args->meshes,
                    "With --report: the training root DB was trained from, to draw the matched "
                    "training views")
        ->check(CLI::ExistingDirectory);
    add_depth_png_options(*cmd, args->input);
    add_segmentation_options(*cmd, args->input);
    cmd->callback([args] { run_scene(*args); });
}

}  // namespace esf::cli
