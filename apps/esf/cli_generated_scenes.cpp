#include "cli_generated_scenes.hpp"

namespace esf::cli {

void add_generated_scene_options(CLI::App& cmd, GeneratedSceneArgs& args) {
    add_seed_option(cmd, args.seed, "Random seed (layouts, cameras, sensor noise)");
    add_threads_option(cmd, args.threads);
    cmd.add_option("--types", args.types, "Scene types in turn (comma-separated; default: all)")
        ->delimiter(',')
        ->check(CLI::IsMember(enum_names<ClutterType>()));
    cmd.add_option("--size-spread", args.size_spread,
                   "Objects other than their models' sizes: each is scaled by a factor drawn "
                   "log-uniformly from [1/(1+S), 1+S] (0: the models' sizes)")
        ->check(CLI::Range(0.0, kClutterMaxSizeSpread))
        ->capture_default_str();
}

void add_generated_scene_model_options(CLI::App& cmd, GeneratedSceneArgs& args) {
    add_catalog_options(cmd, args.catalog, args.no_catalog);
    args.groups.add_to(cmd);
}

}  // namespace esf::cli
