#pragma once
// Internal: what generated scene sets (generated_scenes.cpp) and generated scene sequences
// (scene_sequences.cpp) share: the models of a training root made ready for a ClutterComposer,
// and the output folder.

#include <string>
#include <vector>

#include "esf/render/clutter_scene.hpp"
#include "esf/training/training.hpp"

namespace esf::detail {

/// The models of `root` (plan_models: catalog scaling and groups), their meshes loaded on
/// `threads` threads (each in the import helper) and scaled to metres. A mesh that fails to load
/// is an error naming it.
std::vector<ClutterModel> load_clutter_models(const std::string& root, const std::string& catalog,
                                              bool use_catalog, const GroupSelection& groups,
                                              int threads);

/// Creates `folder` and its parents when missing; throws esf::IoError when it cannot.
void create_output_folder(const std::string& folder);

}  // namespace esf::detail
