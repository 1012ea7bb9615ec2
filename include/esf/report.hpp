#pragma once
// Evaluation reports for people and programs: one folder per evaluation holding
//
//   report.json       every number of the EvaluationReport (machine-readable; see report_json)
//   confusion.png     the confusion matrix as a heat map (row-normalised, class labels drawn
//                     with a built-in 5x7 bitmap font), rows = true class, columns = 1-NN class
//   confusion.svg     the same as vector graphics
//   rank_curves.svg   accuracy vs rank 1..k, one curve per class and the mean (thick), as the
//                     paper's Figs. 15-18
//   index.html        self-contained: the summary, the per-class table (the paper's Table I),
//                     the SVGs inline and the PNG as a data URI
//
// Files are written to a temporary name beside their target and renamed, so a failure leaves
// no partial file. The output depends only on the report and the options (no dates, no paths
// other than those in the report), so equal reports give equal files.

#include <cstdint>
#include <string>
#include <vector>

#include "esf/evaluation.hpp"

namespace esf {

struct ReportOptions {
    std::string title = "esf evaluation";  ///< heading of the HTML page and the figures
    bool include_queries = true;           ///< per-query lines in report.json
};

/// What write_report() wrote (full paths).
struct ReportFiles {
    std::string json;
    std::string confusion_png;
    std::string confusion_svg;
    std::string rank_curves_svg;
    std::string html;
};

/// Writes the five files into `dir` (created with its parents when missing). Throws
/// esf::IoError naming the path when the folder or a file cannot be written.
ReportFiles write_report(const std::string& dir, const EvaluationReport& report,
                         const ReportOptions& options = {});

/// report.json's text: {"title", "mode", "database", "test_set", "descriptor", "weighted", "k",
/// "overall": {"samples", "top1", "top10", "class_top1", "class_top10", "top1_hits",
/// "topk_hits", "rank_curve", "class_rank_curve"}, "classes": [{"class", "samples", "top1",
/// "top10", "confused_with", "confused_count", "failed", "rank_curve"}...], "confusion":
/// {"rows", "columns", "counts"}, "skipped", "missing_classes": [{"class", "samples"}],
/// "failed", "failures": [{"file", "class", "error"}], "timings": {"read_ms", "describe_ms",
/// "match_ms", "total_seconds", "threads"}, "queries": [{"file", "class", "predicted", "rank",
/// "distance"}]}. "top10" and "class_top10" hold the top-k values whatever k is.
std::string report_json(const EvaluationReport& report, const ReportOptions& options = {});

/// The confusion heat map as PNG bytes (8-bit RGB).
std::vector<std::uint8_t> confusion_png(const EvaluationReport& report,
                                        const ReportOptions& options = {});
/// The confusion matrix as an SVG document.
std::string confusion_svg(const EvaluationReport& report, const ReportOptions& options = {});
/// The rank curves as an SVG document.
std::string rank_curves_svg(const EvaluationReport& report, const ReportOptions& options = {});
/// The HTML page (self-contained).
std::string report_html(const EvaluationReport& report, const ReportOptions& options = {});

}  // namespace esf
