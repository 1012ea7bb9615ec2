#pragma once
// What the subcommands that generate table scenes (esf generate-scenes, esf record-scenes) share:
// the models a table is made of (catalog, groups), the seed, the scene types and the thread
// count: their options, and their mapping onto the library's options (SceneGenerationOptions,
// SceneSequenceOptions).

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "esf/core/enum_names.hpp"
#include "esf/render/clutter_scene.hpp"

namespace esf::cli {

struct GeneratedSceneArgs {
    std::uint64_t seed = 0;
    int threads = 0;
    std::vector<std::string> types;  ///< ClutterType names; empty: all
    double size_spread = 0.0;        ///< ClutterOptions::size_spread
    std::string catalog;
    bool no_catalog = false;
    GroupOptions groups;
};

/// --seed, --threads, --types and --size-spread. `args` must outlive `cmd`.
void add_generated_scene_options(CLI::App& cmd, GeneratedSceneArgs& args);

/// --catalog, --no-catalog and the groups (GroupOptions): the models the tables are made of.
/// `args` must outlive `cmd`.
void add_generated_scene_model_options(CLI::App& cmd, GeneratedSceneArgs& args);

/// Sets the fields both commands' options have from `args` (after parsing): the clutter's seed
/// scene types and size spread, the models' groups and catalog, and the thread count.
template <class Options>
void set_generated_scene_options(const GeneratedSceneArgs& args, Options& options) {
    options.clutter.seed = args.seed;
    for (const std::string& type : args.types)
        options.clutter.types.push_back(parse_enum<ClutterType>(type));
    options.clutter.size_spread = args.size_spread;
    options.groups = args.groups.selection();
    options.catalog = args.catalog;
    options.use_catalog = !args.no_catalog;
    options.threads = args.threads;
}

}  // namespace esf::cli
