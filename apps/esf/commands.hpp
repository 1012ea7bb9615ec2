#pragma once
// Each `esf` subcommand lives in its own cmd_<name>.cpp and registers itself here. A command's
// callback parses nothing itself: CLI11 fills its options, the library does the work, and the
// command prints. Errors propagate as exceptions; main() prints them as one line.

#include <CLI/CLI.hpp>

namespace esf::cli {

void add_describe_command(CLI::App& app);
void add_demo_command(CLI::App& app);
void add_train_command(CLI::App& app);
void add_info_command(CLI::App& app);
void add_segment_command(CLI::App& app);
void add_generate_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_classify_command(CLI::App& app);
void add_scene_command(CLI::App& app);
void add_compare_command(CLI::App& app);
void add_eval_command(CLI::App& app);
void add_learn_weights_command(CLI::App& app);
void add_generate_scenes_command(CLI::App& app);
void add_live_command(CLI::App& app);
void add_record_scenes_command(CLI::App& app);
// @commands: one declaration per command above this line

}  // namespace esf::cli
