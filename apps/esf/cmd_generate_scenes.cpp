// esf generate-scenes ROOT -o DIR -n N : cluttered table scenes of the meshes under ROOT, with
// per-pixel labels, scenes.csv for `esf eval --scenes` and truth.json (models and poses).

#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "cli_generated_scenes.hpp"
#include "commands.hpp"
#include "esf/evaluation/generated_scenes.hpp"

namespace esf::cli {

namespace {

struct GenerateScenesArgs {
    std::string root;
    std::string output;
    std::size_t scenes = 100;
    GeneratedSceneArgs generated;
    SensorNoise noise = ClutterOptions{}.noise;
    double min_distance = kClutterMinDistance;
    double max_distance = kClutterMaxDistance;
    double min_elevation = kClutterMinElevation;
    double max_elevation = kClutterMaxElevation;
    bool json = false;
};

void run_generate_scenes(const GenerateScenesArgs& args) {
    SceneGenerationOptions options;
    options.scenes = args.scenes;
    set_generated_scene_options(args.generated, options);
    options.clutter.noise = args.noise;
    options.clutter.min_distance = args.min_distance;
    options.clutter.max_distance = args.max_distance;
    options.clutter.min_elevation = args.min_elevation;
    options.clutter.max_elevation = args.max_elevation;
    std::optional<Progress> bar;
    options.progress = [&](std::size_t done, std::size_t total) {
        if (!bar) bar.emplace("scenes", total);
        bar->update(done);
    };
    const GeneratedSceneSet set = generate_scenes(args.root, args.output, options);
    if (bar) bar->finish();

    const std::vector<ClutterType>& types = clutter_types();
    if (args.json) {
        nlohmann::json out = {{"output", args.output},
                              {"scenes", args.scenes},
                              {"seed", args.generated.seed},
                              {"models", set.models},
                              {"objects", set.objects},
                              {"labelled", set.labelled},
                              {"scene_set", set.files[set.files.size() - 2]},
                              {"truth", set.files.back()}};
        for (std::size_t t = 0; t < types.size(); ++t)
            out["types"][to_string(types[t])] = set.per_type[t];
        std::cout << out.dump(2) << '\n';
        return;
    }
    std::printf("%s: %zu scenes of %zu models, %zu objects (%zu labelled); ", args.output.c_str(),
                args.scenes, set.models, set.objects, set.labelled);
    bool first = true;
    for (std::size_t t = 0; t < types.size(); ++t) {
        if (set.per_type[t] == 0) continue;
        std::printf("%s%zu %s", first ? "" : ", ", set.per_type[t], to_string(types[t]));
        first = false;
    }
    std::printf("\n  evaluate: esf eval DB --scenes %s\n", set.files[set.files.size() - 2].c_str());
}

}  // namespace

void add_generate_scenes_command(CLI::App& app) {
    auto args = std::make_shared<GenerateScenesArgs>();
    CLI::App* cmd = add_command(
        app, "generate-scenes",
        "Generate labelled, cluttered table scenes of the meshes under ROOT",
        "Cluttered table scenes of the meshes under ROOT (as for `esf train`), seen by a\n"
        "Kinect-like sensor 0.6 to 1.5 m away, 25 to 65 degrees above the table: "
        "DIR/scene_NNNN.pcd\n"
        "(organised, x y z rgb label: 0 none, 1 table, 10 k object k), DIR/scenes.csv for\n"
        "`esf eval DB --scenes`, DIR/truth.json (each object's model, pose, visible share).\n"
        "Types in turn: isolated, touching, stacked, occluded, cylindric, mixed (5-7 objects),\n"
        "complex (10-18, touching and leaning); sometimes a wall or a table edge. Use --fold K/N\n"
        "here and `esf train --other-folds K/N` for models the database does not hold. The same\n"
        "seed gives byte-identical files at any thread count.");
    cmd->add_option("root", args->root, "Folder of <category>/<model>.<ext> meshes")
        ->required()
        ->check(CLI::ExistingDirectory);
    cmd->add_option("-o,--output", args->output, "Output folder (created)")->required();
    cmd->add_option("-n,--scenes", args->scenes, "Number of scenes")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    add_generated_scene_options(*cmd, args->generated);
    add_enum_option(*cmd, "--noise", args->noise, "Sensor noise model: kinect or none");
    cmd->add_option("--min-distance", args->min_distance, "Nearest camera, metres")
        ->check(CLI::Range(0.1, 10.0))
        ->capture_default_str();
    cmd->add_option("--max-distance", args->max_distance, "Farthest camera, metres")
        ->check(CLI::Range(0.1, 10.0))
        ->capture_default_str();
    cmd->add_option("--min-elevation", args->min_elevation,
                    "Lowest camera, degrees above the table")
        ->check(CLI::Range(1.0, 89.0))
        ->capture_default_str();
    cmd->add_option("--max-elevation", args->max_elevation,
                    "Highest camera, degrees above the table")
        ->check(CLI::Range(1.0, 89.0))
        ->capture_default_str();
    add_generated_scene_model_options(*cmd, args->generated);
    cmd->add_flag("--json", args->json, "Print the run's summary as one JSON object");
    cmd->callback([args] { run_generate_scenes(*args); });
}

}  // namespace esf::cli
