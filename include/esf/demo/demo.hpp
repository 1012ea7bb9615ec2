#pragma once
// The embedded default: the main job of esf end to end on procedurally generated models, with
// nothing to download (the `esf demo` command).
//
//   1. generate: write_dataset() writes `per_class` models of each of the ten Cat10 categories
//      (shape_generator.hpp) to <work>/train_seed<S>_n<N>/;
//   2. train: esf::train() renders each from the view sphere (`level`) with the Kinect sensor
//      model and stores the ESF descriptors in <work>/demo_seed<S>_n<N>_level<L>.db;
//   3. query: `query_models` HELD-OUT models per category (generator indices per_class and up,
//      never in the database) are rendered with the same sensor model from `query_views` random
//      viewpoints each (directions uniform on the sphere, at the training's camera distance;
//      seeded by (seed, model, view)), and classified by a vote of the 10 nearest views
//      (Recognizer::classify_batch); the paper's Table I (Wohlkinger & Vincze 2011, Sec. V) is
//      computed from them: per class the 1-NN rate (the nearest view has the true class) and the
//      10-NN rate (the true class is among the classes of the 10 nearest views), and the class most
//      often taken for it;
//   4. scene: `scene_objects` held-out models of different categories stand on a table plane,
//      spaced apart, seen by a Kinect-like camera `scene_distance` metres away looking down at
//      `scene_elevation_deg`; the synthetic depth frame (render_scene, with the sensor model) goes
//      through Recognizer::recognize_scene() (segment, then classify each object), and each object
//      found is matched to the placed object most of its pixels show (the frame's labels).
//
// Everything is derived from `seed`: two runs with the same options give the same result (except
// the timings), for any thread count. A run with a given work folder reuses its database (the
// models already trained are skipped), so a second run only queries.
//
// Cost: the defaults (50 training models x 80 views, 400 query views, one scene) take about
// 10 to 15 s on 2 cores (Release), nearly all of it training; memory stays below 200 MB.

#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "esf/core/enum_names.hpp"
#include "esf/core/point_cloud.hpp"
#include "esf/evaluation/evaluation.hpp"
#include "esf/recognition/recognizer.hpp"

namespace esf {

enum class DemoStage { kGenerate, kTrain, kQuery, kScene };

/// "generate", "train", "query", "scene".
template <>
struct EnumNames<DemoStage> {
    static constexpr const char* what = "demo stage";
    static constexpr std::array<EnumName<DemoStage>, 4> table{{{DemoStage::kGenerate, "generate"},
                                                               {DemoStage::kTrain, "train"},
                                                               {DemoStage::kQuery, "query"},
                                                               {DemoStage::kScene, "scene"}}};
};

/// Progress of one stage: reported with done = 0 when a stage starts, as work completes, and
/// with done = total when it ends. Calls are serialised; they come from the calling thread,
/// except while models are generated (write_dataset() reports from its workers).
struct DemoProgress {
    DemoStage stage = DemoStage::kGenerate;
    std::size_t done = 0;
    std::size_t total = 0;  ///< models (generate, train), query views (query), 1 (scene)
    std::size_t views = 0;  ///< train: views described so far in this run
    double seconds = 0.0;   ///< wall time since the stage started
};

struct DemoOptions {
    std::uint64_t seed = 1;
    int per_class = 5;                  ///< training models per category, >= 1
    int level = 1;                      ///< training view sphere: 0 = 20 views, 1 = 80, 2 = 320
    int query_models = 2;               ///< held-out models per category, >= 1
    int query_views = 20;               ///< random viewpoints per held-out model, >= 1
    int scene_objects = 5;              ///< objects on the table, 0 (no scene) to 10
    double scene_distance = 1.0;        ///< metres from the camera to the table centre
    double scene_elevation_deg = 40.0;  ///< camera looks down at this angle (10 to 80)
    /// Folder for the models and the database; empty: a new folder in the system's temporary
    /// directory, removed before run_demo() returns (also when it throws).
    std::string work_dir;
    int threads = 0;  ///< 0 = all cores
    std::function<void(const DemoProgress&)> progress;
};

/// One held-out query view and how it was classified.
struct DemoQuery {
    std::string category;
    std::string model;
    int view = 0;  ///< number of the random viewpoint
    std::size_t points = 0;
    std::string nearest_class;  ///< class of the nearest view (1-NN); empty when failed
    std::string vote_class;     ///< the k-NN vote
    double confidence = 0.0;    ///< the vote's share
    /// Rank of the first of the 10 nearest views with the true class (1 = the 1-NN is right),
    /// 0 when none has it or the view failed.
    std::size_t rank = 0;
    std::string error;  ///< non-empty: the view could not be described
};

/// A model placed in the scene.
struct DemoPlacedObject {
    std::string category;
    std::string model;
    /// Centre of its footprint on the table (world frame, the table is z = 0), metres.
    Eigen::Vector3f position = Eigen::Vector3f::Zero();
    float yaw_deg = 0.0f;                              ///< rotation about the table normal
    Eigen::Vector3f extent = Eigen::Vector3f::Zero();  ///< bounding box of the model, metres
    std::size_t visible_points = 0;                    ///< pixels of the frame that show it
    /// Mean of those points, camera frame (NaN when none is visible).
    Eigen::Vector3f visible_centroid = Eigen::Vector3f::Zero();
    int found_as = -1;  ///< index of the recognised object that matches it; -1: not found
};

/// An object the scene pipeline found, and the placed object it is.
struct DemoFoundObject {
    int placed = -1;           ///< index into DemoScene::placed; -1: mostly table or nothing placed
    double label_share = 0.0;  ///< share of its points that show that placed object
    bool correct = false;      ///< classified as the placed object's category
};

struct DemoScene {
    PointCloud cloud;  ///< the depth frame, camera frame, organised, with render_scene's labels
    Eigen::Isometry3d world_to_camera = Eigen::Isometry3d::Identity();
    std::vector<DemoPlacedObject> placed;
    SceneRecognition recognition;        ///< plane and objects, camera frame
    std::vector<DemoFoundObject> found;  ///< one per recognition.objects
    std::size_t found_placed = 0;        ///< placed objects found
    std::size_t correct = 0;             ///< of them, classified correctly
};

struct DemoSeconds {
    double generate = 0.0, train = 0.0, query = 0.0, scene = 0.0, total = 0.0;
};

struct DemoResult {
    std::uint64_t seed = 0;
    std::vector<std::string> categories;
    std::string work_dir;  ///< where the models and the database were
    bool work_dir_removed = false;
    std::string models_dir;
    std::string database;
    int per_class = 0;
    int level = 0;
    // Training.
    std::size_t train_models = 0;
    std::size_t train_models_existing = 0;  ///< already in the database, not retrained
    std::size_t train_views = 0;            ///< views described in this run
    std::size_t train_views_skipped = 0;
    std::size_t database_views = 0;  ///< views with a descriptor in the database
    // Queries and Table I.
    int query_models = 0;
    int query_views = 0;
    std::vector<DemoQuery> queries;  ///< model by model, view by view
    /// Table I and more: evaluate() of the queries with k = 10 against the ten categories
    /// (per class 1-NN and 10-NN rates, most confused class, 1-NN confusion matrix, rank
    /// curves). Views that could not be described are its failures, counted in no rate.
    EvaluationReport evaluation;
    // The scene.
    DemoScene scene;
    DemoSeconds seconds;  ///< wall time of each stage (the only part not set by the seed)
};

/// Runs the demo. Throws std::invalid_argument for options out of range, esf::IoError when the
/// work folder cannot be made or written, and whatever training or recognition throws.
DemoResult run_demo(const DemoOptions& options = {});

}  // namespace esf
