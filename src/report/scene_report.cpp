#include "esf/report/scene_report.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <system_error>

#include "core/atomic_file.hpp"
#include "core/number_text.hpp"
#include "esf/core/error.hpp"
#include "evaluation/matrix_json.hpp"
#include "report/markup.hpp"

namespace esf {

namespace {

namespace fs = std::filesystem;

using detail::xml_escape;

/// "12.3 %" for a fraction 0.123.
std::string percent(double fraction) { return detail::percent_text(fraction) + " %"; }

nlohmann::json finite_or_null(double x) {
    return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
}

std::string share(std::size_t a, std::size_t b) {
    return b ? percent(static_cast<double>(a) / static_cast<double>(b)) : "-";
}

void object_rows(std::ostringstream& html, const SceneEvaluationReport& report, bool failed_only) {
    html << "<table><tr><th>scene</th><th>type</th><th>object</th><th>points</th>"
            "<th>outcome</th><th>coverage</th><th>purity</th><th>parts</th><th>class</th>"
            "<th>named</th></tr>\n";
    for (const SceneObjectOutcome& o : report.objects) {
        const bool found = o.segmentation.outcome == SegmentOutcome::kFound;
        if (failed_only && o.correct) continue;
        html << "<tr class=\""
             << (o.correct ? "ok"
                 : found   ? "named"
                           : "seg")
             << "\"><td>" << xml_escape(fs::path(o.scene).filename().string()) << "</td><td>"
             << xml_escape(o.type) << "</td><td>" << o.segmentation.object_id << "</td><td>"
             << o.segmentation.points << "</td><td>" << to_string(o.segmentation.outcome)
             << "</td><td>" << percent(o.segmentation.coverage) << "</td><td>"
             << percent(o.segmentation.purity) << "</td><td>" << o.segmentation.parts << "</td><td>"
             << xml_escape(o.true_class.empty() ? "-" : o.true_class) << "</td><td>"
             << xml_escape(o.predicted_class.empty() ? "-" : o.predicted_class) << "</td></tr>\n";
    }
    html << "</table>\n";
}

}  // namespace

namespace {

nlohmann::json pose_or_null(const std::optional<Eigen::Matrix4f>& pose) {
    return pose ? detail::row_major_json(*pose) : nlohmann::json(nullptr);
}

}  // namespace

std::string scene_report_json(const SceneEvaluationReport& report) {
    nlohmann::json out;
    out["scene_set"] = report.scene_set;
    out["database"] = report.database;
    out["grouping"] = report.grouping;
    out["truth"] = report.truth.empty() ? nlohmann::json(nullptr) : nlohmann::json(report.truth);
    out["types"] = nlohmann::json::array();
    for (const SceneTypeSummary& t : report.types)
        out["types"].push_back({{"type", t.type},
                                {"scenes", t.scenes},
                                {"objects", t.objects},
                                {"found", t.found},
                                {"split", t.split},
                                {"merged", t.merged},
                                {"missed", t.missed},
                                {"found_rate", t.found_rate()},
                                {"clusters", t.clusters},
                                {"background_clusters", t.background_clusters},
                                {"shared_clusters", t.shared_clusters},
                                {"labelled", t.labelled},
                                {"correct", t.correct},
                                {"end_to_end", t.end_to_end()},
                                {"posed", t.posed},
                                {"pose_correct", t.pose_correct},
                                {"pose_rate", t.pose_rate()},
                                {"pose_correct_any_model", t.pose_correct_any_model},
                                {"rotations", t.rotation_errors.size()},
                                {"rotation_median_deg", finite_or_null(t.rotation_median())}});
    out["classes"] = nlohmann::json::array();
    for (const SceneClassSummary& c : report.classes)
        out["classes"].push_back({{"class", c.class_name},
                                  {"objects", c.objects},
                                  {"found", c.found},
                                  {"correct", c.correct},
                                  {"found_rate", c.found_rate()},
                                  {"end_to_end", c.end_to_end()},
                                  {"confused_with", c.confused_with},
                                  {"confused_count", c.confused_count}});
    out["objects"] = nlohmann::json::array();
    for (const SceneObjectOutcome& o : report.objects)
        out["objects"].push_back(
            {{"scene", o.scene},
             {"type", o.type},
             {"object_id", o.segmentation.object_id},
             {"points", o.segmentation.points},
             {"outcome", to_string(o.segmentation.outcome)},
             {"coverage", o.segmentation.coverage},
             {"purity", o.segmentation.purity},
             {"parts", o.segmentation.parts},
             {"class", o.true_class},
             {"predicted", o.predicted_class},
             {"correct", o.correct},
             {"model", o.predicted_model.empty() ? nlohmann::json(nullptr)
                                                 : nlohmann::json(o.predicted_model)},
             {"pose", pose_or_null(o.pose)},
             {"add_s", o.pose_judged ? finite_or_null(o.add_s) : nlohmann::json(nullptr)},
             {"pose_judged", o.pose_judged},
             {"pose_correct", o.pose_correct},
             {"add_s_any_model",
              o.pose_judged ? finite_or_null(o.add_s_any_model) : nlohmann::json(nullptr)},
             {"pose_correct_any_model", o.pose_correct_any_model},
             {"rotation_error_deg", finite_or_null(o.rotation_error.value_or(
                                        std::numeric_limits<double>::quiet_NaN()))}});
    out["failures"] = nlohmann::json::array();
    for (const SceneFailure& f : report.failures)
        out["failures"].push_back({{"file", f.file}, {"error", f.error}});
    out["timings"] = {{"segment_ms_per_frame", report.segment_ms},
                      {"recognize_ms_per_frame", report.recognize_ms}};
    return out.dump(2) + "\n";
}

std::string scene_report_html(const SceneEvaluationReport& report, const std::string& title) {
    std::ostringstream html;
    html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>"
         << xml_escape(title)
         << "</title>\n<style>body{font-family:sans-serif;margin:2em;max-width:70em}"
            "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;"
            "padding:2px 8px;text-align:right}th{background:#eee}td:first-child,"
            "th:first-child{text-align:left}tr.seg td{background:#fde0dc}tr.named "
            "td{background:#fff4d6}</style></head><body>\n<h1>"
         << xml_escape(title) << "</h1>\n<p>Scene set " << xml_escape(report.scene_set)
         << (report.database.empty() ? "" : ", database " + xml_escape(report.database))
         << ", grouping " << xml_escape(report.grouping)
         << ". Found: one cluster holds at least 80 % of the object and is at least 80 % that "
            "object; end to end: found and named right.</p>\n";
    const bool poses = !report.truth.empty();
    html << "<h2>By scene type</h2>\n<table><tr><th>scene "
            "type</th><th>scenes</th><th>objects</th><th>found</th>"
            "<th>split</th><th>merged</th><th>missed</th><th>shared clusters</th>"
            "<th>one cluster</th><th>end to end</th>"
         << (poses ? "<th>poses judged</th><th>ADD-S &lt; 0.1 d</th>"
                     "<th>... whatever model named</th><th>rotations judged</th>"
                     "<th>median rotation error</th>"
                   : "")
         << "</tr>\n";
    for (const SceneTypeSummary& t : report.types) {
        html << "<tr><td>" << xml_escape(t.type) << "</td><td>" << t.scenes << "</td><td>"
             << t.objects << "</td><td>" << t.found << "</td><td>" << t.split << "</td><td>"
             << t.merged << "</td><td>" << t.missed << "</td><td>" << t.shared_clusters
             << "</td><td>" << share(t.found, t.objects) << "</td><td>"
             << share(t.correct, t.labelled) << "</td>";
        if (poses)
            html << "<td>" << t.posed << "</td><td>" << share(t.pose_correct, t.posed)
                 << "</td><td>" << share(t.pose_correct_any_model, t.posed) << "</td><td>"
                 << t.rotation_errors.size() << "</td><td>"
                 << (t.rotation_errors.empty()
                         ? std::string("-")
                         : detail::fixed_text(t.rotation_median(), 1) + "&deg;")
                 << "</td>";
        html << "</tr>\n";
    }
    html << "</table>\n";
    if (poses)
        html << "<p>Poses: objects at least half visible whose model the database "
                "holds, against truth.json (meshes under "
             << xml_escape(report.truth)
             << "); ADD-S: mean distance from the model under the true pose to the model under "
                "the found one, as a share of its diameter. Rotations: of the objects named with "
                "their own model where that model has no symmetry (no turn about an axis maps "
                "it onto itself), the angle between the true and the found rotation.</p>\n";
    if (!report.classes.empty()) {
        html << "<h2>By "
                "class</h2>\n<table><tr><th>class</th><th>objects</th><th>found</th><th>named "
                "right</th>"
                "<th>one cluster</th><th>end to end</th><th>most often named instead</th></tr>\n";
        for (const SceneClassSummary& c : report.classes)
            html << "<tr><td>" << xml_escape(c.class_name) << "</td><td>" << c.objects
                 << "</td><td>" << c.found << "</td><td>" << c.correct << "</td><td>"
                 << share(c.found, c.objects) << "</td><td>" << share(c.correct, c.objects)
                 << "</td><td>"
                 << (c.confused_count ? xml_escape(c.confused_with) + " (" +
                                            std::to_string(c.confused_count) + ")"
                                      : std::string("-"))
                 << "</td></tr>\n";
        html << "</table>\n";
    }
    html << "<p>Segmentation " << detail::fixed_text(report.segment_ms, 2)
         << " ms, description and classification " << detail::fixed_text(report.recognize_ms, 2)
         << " ms per frame.</p>\n";
    for (const SceneFailure& f : report.failures)
        html << "<p class=\"failure\">Not evaluated: " << xml_escape(f.file) << ": "
             << xml_escape(f.error) << "</p>\n";
    html << "<h2>Objects not found or not named right</h2>\n";
    object_rows(html, report, true);
    html << "<h2>All objects</h2>\n";
    object_rows(html, report, false);
    html << "</body></html>\n";
    return html.str();
}

SceneReportFiles write_scene_report(const std::string& dir, const SceneEvaluationReport& report,
                                    const std::string& title) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir))
        throw IoError(file_message(dir, 0, "cannot create the report folder"));
    SceneReportFiles files;
    files.json = (fs::path(dir) / "scenes.json").string();
    files.html = (fs::path(dir) / "index.html").string();
    const std::string json = scene_report_json(report);
    const std::string html = scene_report_html(report, title);
    detail::write_file_atomically(files.json, json.data(), json.size());
    detail::write_file_atomically(files.html, html.data(), html.size());
    return files;
}

}  // namespace esf
