#pragma once
// A folder of generated table scenes with their truth (`esf generate-scenes`), from the meshes of
// a training root: the proving ground that segmentation and recognition are judged on, with
// model groups a database does not hold (GroupSelection, both ways).
//
//   DIR/scene_NNNN.pcd  organised 640 x 480, x y z rgb label (binary_compressed); labels as in
//                       the Object Segmentation Database: 0 none, 1 table, 10 k for object k
//   DIR/scenes.csv      scene_file, object_id, class, scene_type: `esf eval DB --scenes`; one row
//                       per object with a label in its frame
//   DIR/truth.json      {"seed", "root", "scenes": [{"file", "type", "wall", "table_edge",
//                       "camera" (world -> camera, 16 numbers row-major), "objects": [{"object_id",
//                       "class", "model" (relative to the root), "pose" (16 numbers row-major: the
//                       mesh file's coordinates -> camera, scale and size included), "scale"
//                       (file units -> metres), "size" (the object's against its model's:
//                       ClutterOptions::size_spread), "visible", "pixels", "labelled",
//                       "placement", "type"}]}]}
//
// Each file is written atomically; the same options give byte-identical files at any thread
// count.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "esf/render/clutter_scene.hpp"
#include "esf/training/training.hpp"

namespace esf {

struct SceneGenerationOptions {
    std::size_t scenes = 100;
    ClutterOptions clutter;  ///< seed, camera, sensor, types
    GroupSelection groups;   ///< the models scenes are made of
    std::string catalog;     ///< as TrainingOptions::catalog
    bool use_catalog = true;
    int threads = 0;  ///< 0 = all cores
    /// Called after each scene written with (scenes done, scenes in all); calls are serialised.
    std::function<void(std::size_t, std::size_t)> progress;
};

struct GeneratedSceneSet {
    std::vector<std::string> files;     ///< written, in order: scenes, scenes.csv, truth.json
    std::size_t models = 0;             ///< models the scenes were drawn from
    std::size_t objects = 0;            ///< placed in all scenes
    std::size_t labelled = 0;           ///< of them: with a label in their frame
    std::vector<std::size_t> per_type;  ///< scenes of each clutter_types() entry
};

/// Loads the models of `root` (plan_models: catalog scaling and groups), composes
/// options.scenes scenes and writes them to `output` (created when missing). Throws
/// std::invalid_argument for bad options or a selection without models, esf::IoError for files
/// that cannot be read or written. A mesh that fails to load is an error naming it.
GeneratedSceneSet generate_scenes(const std::string& root, const std::string& output,
                                  const SceneGenerationOptions& options);

}  // namespace esf
