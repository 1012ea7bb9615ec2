#pragma once
// Evaluation reports for people and programs: one folder per evaluation holding
//
//   report.json       every number of the EvaluationReport (machine-readable; see report_json)
//   confusion.png     the confusion matrix as a bare heat map without text (row-normalised,
//                     one square cell per pair, rows = true class, columns = 1-NN class, the
//                     diagonal framed in red), for programs that want a raster
//   confusion.svg     the confusion matrix with its class labels and counts as real text
//   rank_curves.svg   accuracy vs rank 1..k, one curve per class and the mean (thick), as the
//                     paper's Figs. 15-18
//   index.html        self-contained: the summary, the per-class table (the paper's Table I),
//                     the SVGs inline, and the gallery of misclassified queries when
//                     ReportOptions::gallery has entries (pictures as PNG data URIs, captions
//                     as text)
//
// Files are written to a temporary name beside their target and renamed, so a failure leaves
// no partial file. The output depends only on the report and the options (no dates, no paths
// other than those in the report), so equal reports give equal files.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "esf/evaluation/evaluation.hpp"

namespace esf {

/// One picture of the gallery: a PNG data URI (esf/point_picture.hpp) and what it shows; an
/// empty `png` is drawn as an empty frame with `caption` saying why.
struct GalleryPicture {
    std::string png;
    std::string caption;
};

/// A misclassified query next to the view it was matched to and the nearest view of its class.
struct GalleryEntry {
    std::string file;
    std::string true_class;
    std::string predicted;     ///< class of the nearest view
    std::string matched_view;  ///< "model #view" of the nearest view
    double matched_distance = 0.0;
    std::string true_view;       ///< "model #view" of the nearest view of the true class
    double true_distance = 0.0;  ///< its distance (>= matched_distance)
    std::size_t rank = 0;        ///< the query's rank (0: true class not among the k nearest)
    GalleryPicture query, matched, nearest_true;
    std::string note;  ///< why something is missing; empty when all is there
};

struct ReportOptions {
    std::string title = "esf evaluation";  ///< heading of the HTML page and the figures
    bool include_queries = true;           ///< per-query lines in report.json
    /// Shown in index.html under "Misclassified views" (see esf/view_pictures.hpp).
    std::vector<GalleryEntry> gallery;
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

/// The confusion heat map as PNG bytes (8-bit RGB), without any text.
std::vector<std::uint8_t> confusion_png(const EvaluationReport& report,
                                        const ReportOptions& options = {});
/// The confusion matrix as an SVG document.
std::string confusion_svg(const EvaluationReport& report, const ReportOptions& options = {});
/// The rank curves as an SVG document.
std::string rank_curves_svg(const EvaluationReport& report, const ReportOptions& options = {});
/// The HTML page (self-contained).
std::string report_html(const EvaluationReport& report, const ReportOptions& options = {});

}  // namespace esf
