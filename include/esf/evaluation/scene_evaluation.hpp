#pragma once
// Scene-level evaluation: whole labelled frames through segmentation and recognition, the way
// `esf scene` sees them. Per object: found as one cluster, split, merged or missed
// (esf/segmentation_evaluation.hpp), and whether the cluster that found it was named right
// (end to end). Per scene type and overall: one-cluster rate, splits and merges, clusters that
// hold several objects, end-to-end accuracy, and time per frame.
//
//   SCENES.csv: scene_file, object_id, class [, scene_type]     (header names, any order)
//     scene_file  an organised cloud with a per-point `label` field, relative to the CSV
//     object_id   the object's id in the labels (label / 10 for the Object Segmentation
//                 Database; see LabelScheme)
//     class       its true class
//     scene_type  optional grouping of scenes in the summary ("stacked", "occluded", ...)
// Labelled objects of a scene without a row count for segmentation; they have no class.
//
// Poses: where a truth.json written by `esf generate-scenes` lies beside SCENES.csv, each object
// at least half visible whose model the database holds is judged by ADD-S
// (esf/evaluation/pose_accuracy.hpp) against the pose of the cluster that found it, with the
// meshes under the root truth.json names.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <istream>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "esf/evaluation/segmentation_evaluation.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/segmentation/segmentation.hpp"

namespace esf {

struct SceneObjectLabel {
    std::uint32_t object_id = 0;
    std::string class_name;
};

struct LabelledScene {
    std::string file;  ///< resolved against the CSV's folder
    std::string type;  ///< empty: "all" only
    std::vector<SceneObjectLabel> objects;
};

struct SceneSet {
    std::string path;
    std::vector<LabelledScene> scenes;  ///< in order of first appearance in the CSV
};

/// Reads SCENES.csv (above; parsed by the project's one CSV reader). Throws esf::IoError
/// "path:line: reason" for a missing column, a bad object id, an empty class, one object with
/// two classes, or one scene with two types.
SceneSet read_scene_set(const std::string& csv);
SceneSet read_scene_set(std::istream& in, const std::string& path);

struct SceneEvaluationOptions {
    SegmentationOptions segmentation;
    LabelScheme labels;
    SegmentationCriteria criteria;
    /// Called after each scene with (scenes done, scenes in all); calls are serialised.
    std::function<void(std::size_t, std::size_t)> progress;
};

struct SceneObjectOutcome {
    std::string scene;  ///< file
    std::string type;
    ObjectSegmentation segmentation;
    std::string true_class;       ///< empty: no row in the CSV
    std::string predicted_class;  ///< class of the cluster holding most of it; empty: none
    bool correct = false;         ///< found as one cluster and that cluster named right
    std::string predicted_model;  ///< that cluster's model; empty: none
    /// That cluster's pose (mesh file -> camera: the matched training view's, or with
    /// verification the fitted one); empty: none.
    std::optional<Eigen::Matrix4f> pose;
    /// With a truth.json (esf generate-scenes) and a model the database holds, the object at
    /// least half visible: whether the pose was judged, and its ADD-S / the model's diameter
    /// (infinity when another model or class was named or the object was not found).
    bool pose_judged = false;
    double add_s = 0.0;
    bool pose_correct = false;  ///< judged and add_s < kAddSThreshold
    /// Judged and found with a pose, whatever class and model were named: ADD-S of the object's
    /// own model under that pose (as BOP scores a pose of a known object), over its diameter;
    /// infinity when not found or without a pose. A look-alike named in its place (the three
    /// Coke bottles) counts when its mesh shares the own model's frame and pose.
    double add_s_any_model = 0.0;
    bool pose_correct_any_model = false;  ///< judged and add_s_any_model < kAddSThreshold
    /// Judged, named with its own model, and that model without a symmetry (has_symmetry):
    /// the angle between the true and the predicted rotation, degrees; otherwise empty.
    std::optional<double> rotation_error;
};

struct SceneTypeSummary {
    std::string type;  ///< "all" for the overall row
    std::size_t scenes = 0, objects = 0, found = 0, split = 0, merged = 0, missed = 0;
    std::size_t clusters = 0, background_clusters = 0, shared_clusters = 0;
    std::size_t labelled = 0;      ///< objects with a class
    std::size_t correct = 0;       ///< of them: found and named right
    std::size_t posed = 0;         ///< objects whose pose was judged (truth.json)
    std::size_t pose_correct = 0;  ///< of them: ADD-S below kAddSThreshold of the diameter
    std::size_t pose_correct_any_model = 0;  ///< ... with the own model under the pose found
    /// The rotation errors of the objects that have one (SceneObjectOutcome::rotation_error),
    /// degrees, in the order of the objects.
    std::vector<double> rotation_errors;
    double found_rate() const;       ///< found / objects
    double end_to_end() const;       ///< correct / labelled
    double pose_rate() const;        ///< pose_correct / posed
    double rotation_median() const;  ///< of rotation_errors; NaN when there are none
};

/// One true class over the scenes: how many of its objects were found as one cluster and named
/// right, and the class its found objects were most often named instead.
struct SceneClassSummary {
    std::string class_name;
    std::size_t objects = 0, found = 0;
    std::size_t correct = 0;  ///< found and named right
    /// The commonest wrong name of its found objects ("(none)": found but given no class);
    /// empty when every found object was named right.
    std::string confused_with;
    std::size_t confused_count = 0;
    double found_rate() const;  ///< found / objects
    double end_to_end() const;  ///< correct / objects
};

/// The objects with a true class, summed by class (in name order); of two wrong names as common
/// as each other, the first in name order is the confusion.
std::vector<SceneClassSummary> summarize_classes(std::span<const SceneObjectOutcome> objects);

struct SceneFailure {
    std::string file;
    std::string error;
};

struct SceneEvaluationReport {
    std::string scene_set;
    std::string database;  ///< for reports; evaluate_scenes() leaves it empty
    std::string grouping;  ///< "convexity" or "euclidean"
    std::vector<SceneObjectOutcome> objects;
    std::vector<SceneTypeSummary> types;     ///< by type name, then "all"
    std::vector<SceneClassSummary> classes;  ///< summarize_classes(objects)
    std::vector<SceneFailure> failures;      ///< scenes that could not be read or segmented
    /// truth.json found beside the scene set (poses judged); the mesh root it names.
    std::string truth;
    double segment_ms = 0.0;    ///< mean per frame
    double recognize_ms = 0.0;  ///< mean per frame: describe + classify every cluster
};

/// Evaluates every scene of `set` with `recognizer` (its database's descriptor and settings).
/// A scene that cannot be read, has no labels or does not fit its labels is recorded in
/// `failures` and skipped.
SceneEvaluationReport evaluate_scenes(const Recognizer& recognizer, const SceneSet& set,
                                      const SceneEvaluationOptions& options = {});

}  // namespace esf
