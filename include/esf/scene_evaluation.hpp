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

#include <cstddef>
#include <cstdint>
#include <functional>
#include <istream>
#include <string>
#include <vector>

#include "esf/recognizer.hpp"
#include "esf/segmentation.hpp"
#include "esf/segmentation_evaluation.hpp"

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
};

struct SceneTypeSummary {
    std::string type;  ///< "all" for the overall row
    std::size_t scenes = 0, objects = 0, found = 0, split = 0, merged = 0, missed = 0;
    std::size_t clusters = 0, background_clusters = 0, shared_clusters = 0;
    std::size_t labelled = 0;   ///< objects with a class
    std::size_t correct = 0;    ///< of them: found and named right
    double found_rate() const;  ///< found / objects
    double end_to_end() const;  ///< correct / labelled
};

struct SceneFailure {
    std::string file;
    std::string error;
};

struct SceneEvaluationReport {
    std::string scene_set;
    std::string database;  ///< for reports; evaluate_scenes() leaves it empty
    std::string grouping;  ///< "convexity" or "euclidean"
    std::vector<SceneObjectOutcome> objects;
    std::vector<SceneTypeSummary> types;  ///< by type name, then "all"
    std::vector<SceneFailure> failures;   ///< scenes that could not be read or segmented
    double segment_ms = 0.0;              ///< mean per frame
    double recognize_ms = 0.0;            ///< mean per frame: describe + classify every cluster
};

/// Evaluates every scene of `set` with `recognizer` (its database's descriptor and settings).
/// A scene that cannot be read, has no labels or does not fit its labels is recorded in
/// `failures` and skipped.
SceneEvaluationReport evaluate_scenes(const Recognizer& recognizer, const SceneSet& set,
                                      const SceneEvaluationOptions& options = {});

}  // namespace esf
