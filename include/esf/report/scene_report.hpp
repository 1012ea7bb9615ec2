#pragma once
// Reports of a scene evaluation (esf/scene_evaluation.hpp) for programs and people:
//
//   scenes.json   every number: {"scene_set", "database", "grouping", "types": [{"type",
//                 "scenes", "objects", "found", "split", "merged", "missed", "found_rate",
//                 "clusters", "background_clusters", "shared_clusters", "labelled", "correct",
//                 "end_to_end"}...] ("all" last), "objects": [{"scene", "type", "object_id",
//                 "points", "outcome", "coverage", "purity", "parts", "class", "predicted",
//                 "correct"}...], "failures": [{"file", "error"}], "timings":
//                 {"segment_ms_per_frame", "recognize_ms_per_frame"}}
//   index.html    self-contained: the summary per scene type, then every object that was not
//                 found or not named right, then all objects
//
// Files are written through a temporary name and a rename; equal reports give equal files.

#include <string>

#include "esf/evaluation/scene_evaluation.hpp"

namespace esf {

struct SceneReportFiles {
    std::string json;
    std::string html;
};

std::string scene_report_json(const SceneEvaluationReport& report);
std::string scene_report_html(const SceneEvaluationReport& report, const std::string& title);

/// Writes scenes.json and index.html into `dir` (created when missing). Throws esf::IoError
/// naming the path when the folder or a file cannot be written.
SceneReportFiles write_scene_report(const std::string& dir, const SceneEvaluationReport& report,
                                    const std::string& title);

}  // namespace esf
