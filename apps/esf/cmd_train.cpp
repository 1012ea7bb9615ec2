// esf train ROOT -o DB [--descriptor NAME] : render every CAD model under ROOT, describe every
// view (ESF or a baseline descriptor), store it all.

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "cli_common.hpp"
#include "commands.hpp"
#include "core/elapsed_time.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"

namespace esf::cli {

namespace {

struct TrainArgs {
    std::string root;
    std::string output;
    std::string descriptor = kTrainingDescriptor;
    int level = 1;
    int threads = 0;
    std::uint64_t seed = 0;
    int samples = kEsfSamples;
    SensorNoise noise = default_training_render().noise;
    std::string camera = "kinect";
    double fill = 0.5;
    double distance = kTrainingCameraDistance;
    double max_distance = kTrainingMaxCameraDistance;
    double angles_weight = kEsfAnglesWeight;
    double primitive_weight = kEsfPrimitiveWeight;
    double min_elevation = kTrainingMinElevation;
    double max_elevation = 90.0;
    std::size_t min_points = 50;
    std::size_t occlusions = kTrainingOcclusions;
    std::size_t surface_points = kTrainingSurfacePoints;
    std::string catalog;
    bool no_catalog = false;
    GroupOptions groups;
    bool json = false;
};

using detail::seconds_since;

void run_train(const TrainArgs& args) {
    TrainingOptions options;
    options.render.level = args.level;
    options.render.noise = args.noise;
    options.render.camera =
        args.camera == "pcl" ? CameraIntrinsics::pcl_renderer() : CameraIntrinsics::kinect();
    options.render.fill_fraction = args.fill;
    if (args.distance > 0.0)
        options.render.distance = args.distance;
    else
        options.render.distance.reset();
    if (args.max_distance > 0.0)
        options.render.max_distance = args.max_distance;
    else
        options.render.max_distance.reset();
    options.render.min_elevation = args.min_elevation;
    options.render.max_elevation = args.max_elevation;
    options.descriptor = args.descriptor;
    options.esf.samples = args.samples;
    options.descriptor_options.samples = args.samples;
    options.descriptor_options.angles_weight = args.angles_weight;
    options.descriptor_options.primitive_weight = args.primitive_weight;
    options.seed = args.seed;
    options.min_points = args.min_points;
    options.occlusions = args.occlusions;
    options.surface_points = args.surface_points;
    options.threads = args.threads;
    options.catalog = args.catalog;
    options.use_catalog = !args.no_catalog;
    options.groups = args.groups.selection();

    const auto start = std::chrono::steady_clock::now();
    std::optional<Progress> bar;
    std::size_t existing = 0;
    options.progress = [&](const TrainingProgress& p) {
        if (!bar) {
            existing = p.models_existing;
            bar.emplace("train", p.models_total - existing);
        }
        const double elapsed = seconds_since(start);
        const double rate =
            elapsed > 0 ? static_cast<double>(p.views + p.views_skipped) / elapsed : 0.0;
        char detail[96];
        std::snprintf(detail, sizeof detail, "models, %.0f views/s, %zu skipped", rate,
                      p.views_skipped);
        bar->update(p.models_done - existing, detail);
    };

    require_descriptor(options.descriptor);  // before the database is created
    // A group or category that is not there, likewise.
    if (!options.groups.empty())
        plan_models(args.root, options.catalog, options.use_catalog, options.groups);
    Database db(args.output, OpenMode::kWrite);
    const TrainingResult result = train(args.root, db, options);
    if (bar) bar->finish();
    const double elapsed = seconds_since(start);

    for (const auto& f : result.failures)
        std::fprintf(stderr, "esf: warning: %s failed: %s\n", f.model.c_str(), f.error.c_str());
    const double rate =
        elapsed > 0 ? static_cast<double>(result.views + result.views_skipped) / elapsed : 0.0;
    if (args.json) {
        nlohmann::json out = {{"database", args.output},
                              {"descriptor", args.descriptor},
                              {"models", result.models_total},
                              {"models_trained", result.models_trained},
                              {"models_existing", result.models_existing},
                              {"models_failed", result.models_failed},
                              {"views", result.views},
                              {"skipped_views", result.views_skipped},
                              {"seconds", elapsed},
                              {"views_per_second", rate}};
        out["failures"] = nlohmann::json::array();
        for (const auto& f : result.failures)
            out["failures"].push_back({{"model", f.model}, {"error", f.error}});
        std::cout << out.dump(2) << '\n';
    } else {
        std::printf(
            "%s: trained %zu models (%zu views, %zu skipped) with %s in %.1f s, %.0f views/s",
            args.output.c_str(), result.models_trained, result.views, result.views_skipped,
            args.descriptor.c_str(), elapsed, rate);
        if (result.models_existing) std::printf("; %zu already stored", result.models_existing);
        if (result.models_failed) std::printf("; %zu failed", result.models_failed);
        std::printf("\n");
    }
    // As for a batch of clouds: the good models are stored, the run reports the others.
    if (result.models_failed) throw ExitStatus{kExitRuntime};
}

}  // namespace

void add_train_command(CLI::App& app) {
    auto args = std::make_shared<TrainArgs>();
    CLI::App* cmd = add_command(
        app, "train", "Build a training database from the rendered views of CAD models",
        "Build a training database from CAD models: ROOT/<category>/<model>.<ext>\n"
        "(ply obj off stl gltf glb dae 3ds fbx). Every model is rendered from the view sphere\n"
        "(level 1: 80 cameras; by default the 44 above the model's xy plane, each 0.6 to 1.2 m\n"
        "away), every view is described with ESF + surface angles (esf-angles; --descriptor esf\n"
        "for the paper's ESF, or a baseline: the same views, seeds and noise for every\n"
        "descriptor), and views, poses, descriptors\n"
        "and all settings go into one SQLite file, one transaction per model. Run it again to\n"
        "resume an interrupted run or to add new models; other settings are refused.\n"
        "With ROOT/catalog.csv (or --catalog), non-metric models are scaled to the median size\n"
        "of their category's metric models and keep the catalog's shape group.\n"
        "Meshes that fail to load are reported and stored as failed (retried next run); the\n"
        "exit status is then 2.");
    cmd->add_option("root", args->root, "Folder of <category>/<model>.<ext> meshes")
        ->required()
        ->check(CLI::ExistingDirectory);
    cmd->add_option("-o,--output", args->output, "Database file (created or resumed)")->required();
    std::string names;
    for (const auto& n : descriptor_names()) names += (names.empty() ? "" : ", ") + n;
    cmd->add_option("--descriptor", args->descriptor, "Descriptor to store: " + names)
        ->check(CLI::IsMember(descriptor_names()))
        ->capture_default_str();
    cmd->add_option("--level", args->level,
                    "View sphere subdivisions: 0 = 20, 1 = 80, 2 = 320 views")
        ->check(CLI::Range(0, 4))
        ->capture_default_str();
    add_threads_option(*cmd, args->threads);
    add_seed_option(*cmd, args->seed, "Random seed (sensor noise, descriptor sampling)");
    cmd->add_option("--samples", args->samples,
                    "Point triples per view of esf, esf-angles, sdvs, d2 (the paper's number)")
        ->capture_default_str();
    cmd->add_option("--angles-weight", args->angles_weight,
                    "esf-angles: weight of the surface angle histograms against ESF's 1")
        ->check(CLI::Range(0.0, 100.0))
        ->capture_default_str();
    cmd->add_option("--primitive-weight", args->primitive_weight,
                    "esf-angles: weight of the cylinder-box contrast (primitive fit) against "
                    "ESF's 1")
        ->check(CLI::Range(0.0, 100.0))
        ->capture_default_str();
    add_enum_option(*cmd, "--noise", args->noise, "Sensor noise model: kinect or none");
    cmd->add_option("--camera", args->camera,
                    "Camera: kinect (640x480, f 525) or pcl (PCL's renderer, 150x150)")
        ->check(CLI::IsMember({"kinect", "pcl"}))
        ->capture_default_str();
    cmd->add_option("--distance", args->distance,
                    "Nearest camera distance from the model's centre, metres (a table-top sensor; "
                    "models too large for it are seen from 1.5 x their radius); 0: use --fill "
                    "instead")
        ->check(CLI::Range(0.0, 100.0))
        ->capture_default_str();
    cmd->add_option("--max-distance", args->max_distance,
                    "Largest camera distance, metres: each view's distance is drawn from "
                    "[--distance, --max-distance]; at or below --distance (or 0): every view at "
                    "--distance")
        ->check(CLI::Range(0.0, 100.0))
        ->capture_default_str();
    cmd->add_option("--min-elevation", args->min_elevation,
                    "Lowest camera elevation above the model's xy plane, degrees")
        ->check(CLI::Range(-90.0, 90.0))
        ->capture_default_str();
    cmd->add_option("--max-elevation", args->max_elevation,
                    "Highest camera elevation above the model's xy plane, degrees")
        ->check(CLI::Range(-90.0, 90.0))
        ->capture_default_str();
    cmd->add_option("--fill", args->fill,
                    "With --distance 0: fraction of the image side the object spans (PCL's "
                    "renderer: the object fills its 150x150 image)")
        ->check(CLI::Range(0.01, 1.0))
        ->capture_default_str();
    cmd->add_option("--min-points", args->min_points,
                    "Views with fewer points are skipped (and counted)")
        ->check(CLI::Range(3, 1000000))
        ->capture_default_str();
    cmd->add_option("--occlusions", args->occlusions,
                    "Each view is also described this many times with part of it hidden (an edge "
                    "across the image, 20 to 50 % of its points, as a nearer object hides them): "
                    "more signatures of the view, which a partly hidden object matches (0: none)")
        ->check(CLI::Range(std::size_t{0}, kMaxTrainingOcclusions))
        ->capture_default_str();
    cmd->add_option("--surface-points", args->surface_points,
                    "Samples of each model's surface stored for verification (0: none; "
                    "recognition then verifies only with --verify-meshes)")
        ->check(CLI::Range(std::size_t{0}, kMaxModelSurfacePoints))
        ->capture_default_str();
    add_catalog_options(*cmd, args->catalog, args->no_catalog);
    args->groups.add_to(*cmd);
    cmd->add_flag("--json", args->json, "Print the run's summary as one JSON object");
    cmd->callback([args] { run_train(*args); });
}

}  // namespace esf::cli
