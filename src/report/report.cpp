#include "esf/report/report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <system_error>

#include "core/atomic_file.hpp"
#include "core/number_text.hpp"
#include "esf/core/error.hpp"
#include "io/png_writer.hpp"
#include "report/markup.hpp"

namespace esf {

namespace {

namespace fs = std::filesystem;

// ---- text helpers ---------------------------------------------------------------------------

using detail::xml_escape;

using detail::fixed_text;
using detail::percent_text;

void write_file(const fs::path& path, const void* data, std::size_t size) {
    detail::write_file_atomically(path, data, size);
}

void write_text(const fs::path& path, const std::string& text) {
    write_file(path, text.data(), text.size());
}

// ---- colours --------------------------------------------------------------------------------

struct Rgb {
    std::uint8_t r = 0, g = 0, b = 0;
};

/// White -> dark blue (the "Blues" ramp) for a fraction in [0, 1].
Rgb heat(double t) {
    static const std::array<Rgb, 5> kStops = {
        {{247, 251, 255}, {198, 219, 239}, {107, 174, 214}, {33, 113, 181}, {8, 48, 107}}};
    t = std::clamp(t, 0.0, 1.0) * static_cast<double>(kStops.size() - 1);
    const auto i = std::min(static_cast<std::size_t>(t), kStops.size() - 2);
    const double f = t - static_cast<double>(i);
    auto mix = [f](std::uint8_t a, std::uint8_t b) {
        return static_cast<std::uint8_t>(std::lround((1.0 - f) * a + f * b));
    };
    return {mix(kStops[i].r, kStops[i + 1].r), mix(kStops[i].g, kStops[i + 1].g),
            mix(kStops[i].b, kStops[i + 1].b)};
}

std::string css(Rgb c) {
    char buffer[8];
    std::snprintf(buffer, sizeof buffer, "#%02x%02x%02x", c.r, c.g, c.b);
    return buffer;
}

/// Distinct line colours (Tableau 10 then its light variants).
const std::array<const char*, 20> kPalette = {
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
    "#7f7f7f", "#bcbd22", "#17becf", "#aec7e8", "#ffbb78", "#98df8a", "#ff9896",
    "#c5b0d5", "#c49c94", "#f7b6d2", "#c7c7c7", "#dbdb8d", "#9edae5"};

// ---- text sizes -----------------------------------------------------------------------------

/// Width of a character of the SVG's labels at `scale` (sans-serif at 6 * scale + 1 px runs
/// narrower than this, so labels fit the space laid out for them).
constexpr int kCharAdvance = 6;

int text_width(const std::string& s, int scale) {
    return static_cast<int>(s.size()) * kCharAdvance * scale;
}

/// An 8-bit RGB raster.
class Image {
  public:
    Image(int width, int height) : width_(width), height_(height) {
        pixels_.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3, 255);
    }
    int width() const { return width_; }
    int height() const { return height_; }
    const std::vector<std::uint8_t>& pixels() const { return pixels_; }

    void set(int x, int y, Rgb c) {
        if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
        std::uint8_t* p = &pixels_[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                                    static_cast<std::size_t>(x)) *
                                   3];
        p[0] = c.r;
        p[1] = c.g;
        p[2] = c.b;
    }
    void fill(int x, int y, int w, int h, Rgb c) {
        for (int j = y; j < y + h; ++j)
            for (int i = x; i < x + w; ++i) set(i, j, c);
    }

  private:
    int width_, height_;
    std::vector<std::uint8_t> pixels_;
};

// ---- PNG ------------------------------------------------------------------------------------

std::vector<std::uint8_t> encode_png(const Image& image) {
    return detail::encode_png(image.pixels(), static_cast<std::uint32_t>(image.width()),
                              static_cast<std::uint32_t>(image.height()), 3, 8);
}

// ---- confusion layout (shared by the PNG and the SVG) ---------------------------------------

struct ConfusionLayout {
    std::size_t rows = 0, columns = 0;
    int cell = 24;
    int label_scale = 2;    // font scale of the class labels
    int left = 0, top = 0;  // the matrix's top-left corner
    int width = 0, height = 0;
    std::vector<std::size_t> row_totals;
    std::string title, subtitle;
};

ConfusionLayout confusion_layout(const EvaluationReport& report, const ReportOptions& options) {
    ConfusionLayout l;
    l.rows = report.confusion_rows.size();
    l.columns = report.confusion_columns.size();
    const auto n = static_cast<int>(std::max<std::size_t>({l.rows, l.columns, 1}));
    l.cell = std::clamp(720 / n, 16, 40);
    l.label_scale = l.cell >= 20 ? 2 : 1;
    std::size_t row_chars = 10, column_chars = 10;  // "true class", "1-nn class"
    for (const auto& s : report.confusion_rows) row_chars = std::max(row_chars, s.size());
    for (const auto& s : report.confusion_columns) column_chars = std::max(column_chars, s.size());
    const int char_w = kCharAdvance * l.label_scale;
    l.title = options.title;
    l.subtitle = "confusion: rows = true class, columns = 1-nn class, colour = % of the row";
    l.left = 12 + static_cast<int>(row_chars) * char_w + 8;
    l.top = 12 + 2 * 8 + 6 + 8 + 12 + static_cast<int>(column_chars) * char_w + 8;
    const int matrix_w = static_cast<int>(l.columns) * l.cell,
              matrix_h = static_cast<int>(l.rows) * l.cell;
    l.width = std::max({l.left + matrix_w + 90, 12 + text_width(l.title, 2) + 12,
                        12 + text_width(l.subtitle, 1) + 12});
    l.height = l.top + matrix_h + 12 + 2 * 8 + 24;
    l.row_totals.assign(l.rows, 0);
    for (std::size_t r = 0; r < l.rows; ++r)
        for (std::size_t c = 0; c < l.columns; ++c) l.row_totals[r] += report.confusion_at(r, c);
    return l;
}

double cell_fraction(const EvaluationReport& report, const ConfusionLayout& l, std::size_t r,
                     std::size_t c) {
    return l.row_totals[r] ? static_cast<double>(report.confusion_at(r, c)) /
                                 static_cast<double>(l.row_totals[r])
                           : 0.0;
}

/// Luminance-based choice of the text colour on a cell.
bool dark(Rgb c) { return 0.299 * c.r + 0.587 * c.g + 0.114 * c.b < 128.0; }

// ---- JSON -----------------------------------------------------------------------------------

nlohmann::json report_object(const EvaluationReport& r, const ReportOptions& options) {
    nlohmann::json j;
    j["title"] = options.title;
    j["mode"] = r.mode;
    j["database"] = r.database;
    j["test_set"] = r.test_set;
    j["descriptor"] = r.descriptor;
    j["weighted"] = r.weighted;
    j["k"] = r.k;
    j["overall"] = {{"samples", r.samples},
                    {"top1", r.top1},
                    {"top10", r.topk},
                    {"class_top1", r.class_top1},
                    {"class_top10", r.class_topk},
                    {"top1_hits", r.top1_hits},
                    {"topk_hits", r.topk_hits},
                    {"rank_curve", r.rank_curve},
                    {"class_rank_curve", r.class_rank_curve}};
    nlohmann::json classes = nlohmann::json::array();
    for (const ClassMetrics& c : r.classes)
        classes.push_back({{"class", c.class_name},
                           {"samples", c.samples},
                           {"top1", c.top1},
                           {"top10", c.topk},
                           {"confused_with", c.confused_with},
                           {"confused_count", c.confused_count},
                           {"failed", c.failed},
                           {"rank_curve", c.rank_curve}});
    j["classes"] = std::move(classes);
    nlohmann::json counts = nlohmann::json::array();
    for (std::size_t row = 0; row < r.confusion_rows.size(); ++row) {
        nlohmann::json line = nlohmann::json::array();
        for (std::size_t c = 0; c < r.confusion_columns.size(); ++c)
            line.push_back(r.confusion_at(row, c));
        counts.push_back(std::move(line));
    }
    j["confusion"] = {
        {"rows", r.confusion_rows}, {"columns", r.confusion_columns}, {"counts", counts}};
    j["skipped"] = r.skipped;
    nlohmann::json missing = nlohmann::json::array();
    for (const SkippedClass& s : r.missing_classes)
        missing.push_back({{"class", s.class_name}, {"samples", s.samples}});
    j["missing_classes"] = std::move(missing);
    j["failed"] = r.failed;
    nlohmann::json failures = nlohmann::json::array();
    for (const QueryFailure& f : r.failures)
        failures.push_back({{"file", f.file}, {"class", f.true_class}, {"error", f.error}});
    j["failures"] = std::move(failures);
    j["timings"] = {{"read_ms", r.read_ms},
                    {"describe_ms", r.describe_ms},
                    {"match_ms", r.match_ms},
                    {"total_seconds", r.total_seconds},
                    {"threads", r.threads}};
    if (options.include_queries) {
        nlohmann::json queries = nlohmann::json::array();
        for (const QueryResult& q : r.queries)
            queries.push_back({{"file", q.file},
                               {"class", q.true_class},
                               {"predicted", q.predicted},
                               {"rank", q.rank},
                               {"distance", q.distance}});
        j["queries"] = std::move(queries);
    }
    return j;
}

}  // namespace

std::string report_json(const EvaluationReport& report, const ReportOptions& options) {
    return report_object(report, options).dump(2) + "\n";
}

std::vector<std::uint8_t> confusion_png(const EvaluationReport& report,
                                        const ReportOptions& options) {
    // The cells only: labels and counts are text, and text lives in confusion.svg.
    const ConfusionLayout l = confusion_layout(report, options);
    constexpr int kMargin = 8, kBarWidth = 200, kBarHeight = 12;
    const int matrix_w = static_cast<int>(l.columns) * l.cell,
              matrix_h = static_cast<int>(l.rows) * l.cell;
    Image image(std::max(2 * kMargin + matrix_w + 1, 2 * kMargin + kBarWidth),
                kMargin + matrix_h + 1 + 10 + kBarHeight + kMargin);
    const Rgb grid{200, 200, 200}, accent{200, 30, 30};
    const int left = kMargin, top = kMargin;
    for (std::size_t r = 0; r < l.rows; ++r)
        for (std::size_t c = 0; c < l.columns; ++c)
            image.fill(left + static_cast<int>(c) * l.cell, top + static_cast<int>(r) * l.cell,
                       l.cell, l.cell, heat(cell_fraction(report, l, r, c)));
    // Grid lines, and a frame around the cells of the true class (the diagonal).
    for (std::size_t c = 0; c <= l.columns; ++c)
        image.fill(left + static_cast<int>(c) * l.cell, top, 1, matrix_h + 1, grid);
    for (std::size_t r = 0; r <= l.rows; ++r)
        image.fill(left, top + static_cast<int>(r) * l.cell, matrix_w + 1, 1, grid);
    for (std::size_t r = 0; r < l.rows; ++r) {
        const auto it = std::find(report.confusion_columns.begin(), report.confusion_columns.end(),
                                  report.confusion_rows[r]);
        if (it == report.confusion_columns.end()) continue;
        const int x = left + static_cast<int>(it - report.confusion_columns.begin()) * l.cell,
                  y = top + static_cast<int>(r) * l.cell;
        image.fill(x, y, l.cell + 1, 2, accent);
        image.fill(x, y + l.cell - 1, l.cell + 1, 2, accent);
        image.fill(x, y, 2, l.cell + 1, accent);
        image.fill(x + l.cell - 1, y, 2, l.cell + 1, accent);
    }
    // Colour bar under the matrix: 0 % (left) .. 100 % (right) of a row.
    const int bar_y = top + matrix_h + 1 + 10;
    for (int i = 0; i < kBarWidth; ++i)
        image.fill(left + i, bar_y, 1, kBarHeight, heat(static_cast<double>(i) / (kBarWidth - 1)));
    return encode_png(image);
}

std::string confusion_svg(const EvaluationReport& report, const ReportOptions& options) {
    const ConfusionLayout l = confusion_layout(report, options);
    const int font = 6 * l.label_scale + 1;
    std::ostringstream o;
    o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << l.width << "\" height=\""
      << l.height << "\" viewBox=\"0 0 " << l.width << ' ' << l.height
      << "\" font-family=\"sans-serif\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"12\" y=\"26\" font-size=\"15\">" << xml_escape(l.title) << "</text>\n"
      << "<text x=\"12\" y=\"42\" font-size=\"11\">" << xml_escape(l.subtitle) << "</text>\n";
    for (std::size_t c = 0; c < l.columns; ++c) {
        const double x = l.left + (static_cast<double>(c) + 0.5) * l.cell + font / 3.0;
        o << "<text transform=\"translate(" << x << ',' << l.top - 8
          << ") rotate(-90)\" font-size=\"" << font << "\">"
          << xml_escape(report.confusion_columns[c]) << "</text>\n";
    }
    for (std::size_t r = 0; r < l.rows; ++r) {
        const double y = l.top + (static_cast<double>(r) + 0.5) * l.cell + font / 3.0;
        o << "<text x=\"" << l.left - 8 << "\" y=\"" << y << "\" font-size=\"" << font
          << "\" text-anchor=\"end\">" << xml_escape(report.confusion_rows[r]) << "</text>\n";
    }
    for (std::size_t r = 0; r < l.rows; ++r)
        for (std::size_t c = 0; c < l.columns; ++c) {
            const int x = l.left + static_cast<int>(c) * l.cell,
                      y = l.top + static_cast<int>(r) * l.cell;
            const double f = cell_fraction(report, l, r, c);
            const Rgb colour = heat(f);
            const bool diagonal = report.confusion_rows[r] == report.confusion_columns[c];
            const std::size_t count = report.confusion_at(r, c);
            o << "<rect x=\"" << x << "\" y=\"" << y << "\" width=\"" << l.cell << "\" height=\""
              << l.cell << "\" fill=\"" << css(colour) << "\" stroke=\""
              << (diagonal ? "#c81e1e" : "#c8c8c8") << "\" stroke-width=\"" << (diagonal ? 2 : 1)
              << "\"><title>" << xml_escape(report.confusion_rows[r]) << " -&gt; "
              << xml_escape(report.confusion_columns[c]) << ": " << count << " (" << percent_text(f)
              << " %)</title></rect>\n";
            if (count)
                o << "<text x=\"" << x + l.cell / 2.0 << "\" y=\"" << y + l.cell / 2.0 + 4
                  << "\" font-size=\"10\" text-anchor=\"middle\" fill=\""
                  << (dark(colour) ? "white" : "black") << "\">" << count << "</text>\n";
        }
    // Colour bar under the matrix: 0 % .. 100 % of a row.
    const int bar_y = l.top + static_cast<int>(l.rows) * l.cell + 12;
    o << "<defs><linearGradient id=\"confusion-scale\">";
    for (int i = 0; i <= 4; ++i)
        o << "<stop offset=\"" << i * 25 << "%\" stop-color=\"" << css(heat(i / 4.0)) << "\"/>";
    o << "</linearGradient></defs>\n"
      << "<text x=\"" << l.left << "\" y=\"" << bar_y + 13 << "\" font-size=\"12\">0 %</text>\n"
      << "<rect x=\"" << l.left + 30 << "\" y=\"" << bar_y << "\" width=\"200\" height=\"18\" "
      << "fill=\"url(#confusion-scale)\" stroke=\"#c8c8c8\"/>\n"
      << "<text x=\"" << l.left + 236 << "\" y=\"" << bar_y + 13
      << "\" font-size=\"12\">100 % of the row</text>\n"
      << "</svg>\n";
    return o.str();
}

std::string rank_curves_svg(const EvaluationReport& report, const ReportOptions& options) {
    const int width = 900, height = 520;
    const int left = 64, right = 620, top = 48, bottom = 460;
    const std::size_t k = std::max<std::size_t>(report.k, 1);
    auto px = [&](double rank) {
        return k == 1 ? (left + right) / 2.0
                      : left + (rank - 1.0) / static_cast<double>(k - 1) * (right - left);
    };
    auto py = [&](double v) { return bottom - v * (bottom - top); };
    std::ostringstream o;
    o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" viewBox=\"0 0 " << width << ' ' << height << "\" font-family=\"sans-serif\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << left << "\" y=\"28\" font-size=\"16\">" << xml_escape(options.title)
      << ": accuracy vs rank</text>\n";
    // Grid, ticks and axis labels.
    for (int i = 0; i <= 10; ++i) {
        const double y = py(i / 10.0);
        o << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << right << "\" y2=\"" << y
          << "\" stroke=\"#e0e0e0\"/>\n"
          << "<text x=\"" << left - 6 << "\" y=\"" << y + 4
          << "\" font-size=\"11\" text-anchor=\"end\">" << i * 10 << "</text>\n";
    }
    for (std::size_t r = 1; r <= k; ++r) {
        const double x = px(static_cast<double>(r));
        o << "<line x1=\"" << x << "\" y1=\"" << top << "\" x2=\"" << x << "\" y2=\"" << bottom
          << "\" stroke=\"#f0f0f0\"/>\n"
          << "<text x=\"" << x << "\" y=\"" << bottom + 16
          << "\" font-size=\"11\" text-anchor=\"middle\">" << r << "</text>\n";
    }
    o << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << right - left << "\" height=\""
      << bottom - top << "\" fill=\"none\" stroke=\"black\"/>\n"
      << "<text x=\"" << (left + right) / 2 << "\" y=\"" << bottom + 36
      << "\" font-size=\"13\" text-anchor=\"middle\">rank (true class among the r nearest "
         "views)</text>\n"
      << "<text transform=\"translate(20," << (top + bottom) / 2
      << ") rotate(-90)\" font-size=\"13\" text-anchor=\"middle\">accuracy (%)</text>\n";
    auto polyline = [&](const std::vector<double>& curve, const std::string& colour, double w,
                        const std::string& dash, const std::string& name) {
        if (curve.empty()) return;
        o << "<g><title>" << xml_escape(name) << "</title><polyline fill=\"none\" stroke=\""
          << colour << "\" stroke-width=\"" << w << "\"";
        if (!dash.empty()) o << " stroke-dasharray=\"" << dash << "\"";
        o << " points=\"";
        for (std::size_t r = 0; r < curve.size(); ++r)
            o << (r ? " " : "") << px(static_cast<double>(r + 1)) << ',' << py(curve[r]);
        o << "\"/>";
        for (std::size_t r = 0; r < curve.size(); ++r)
            o << "<circle cx=\"" << px(static_cast<double>(r + 1)) << "\" cy=\"" << py(curve[r])
              << "\" r=\"" << w + 1 << "\" fill=\"" << colour << "\"/>";
        o << "</g>\n";
    };
    // Legend to the right of the plot: one line per class, then the means.
    const std::size_t n = report.classes.size();
    const double line_h = std::min(18.0, (bottom - top - 40.0) / static_cast<double>(n + 2));
    double ly = top + 8;
    auto legend = [&](const std::string& colour, double w, const std::string& dash,
                      const std::string& text) {
        o << "<line x1=\"" << right + 16 << "\" y1=\"" << ly << "\" x2=\"" << right + 40
          << "\" y2=\"" << ly << "\" stroke=\"" << colour << "\" stroke-width=\"" << w << "\"";
        if (!dash.empty()) o << " stroke-dasharray=\"" << dash << "\"";
        o << "/><text x=\"" << right + 46 << "\" y=\"" << ly + 4 << "\" font-size=\""
          << std::min(12.0, line_h - 1) << "\">" << xml_escape(text) << "</text>\n";
        ly += line_h;
    };
    for (std::size_t c = 0; c < n; ++c) {
        const ClassMetrics& m = report.classes[c];
        if (m.samples == 0) continue;
        const std::string colour = kPalette[c % kPalette.size()];
        const std::string dash = c / kPalette.size() % 2 ? "5,3" : "";
        polyline(m.rank_curve, colour, 1.5, dash, m.class_name);
        legend(colour, 1.5, dash,
               m.class_name + " (" + std::to_string(m.samples) + "): " + percent_text(m.top1) +
                   " -> " + percent_text(m.topk));
    }
    polyline(report.class_rank_curve, "black", 3.0, "", "mean over classes");
    legend("black", 3.0, "",
           "mean over classes: " + percent_text(report.class_top1) + " -> " +
               percent_text(report.class_topk));
    polyline(report.rank_curve, "#555555", 2.0, "6,3", "per sample");
    legend("#555555", 2.0, "6,3",
           "per sample: " + percent_text(report.top1) + " -> " + percent_text(report.topk));
    o << "</svg>\n";
    return o.str();
}

namespace {

/// The file's folder and name ("bowl/view_003.pcd"), enough to tell the queries apart.
std::string short_path(const std::string& file) {
    const fs::path path(file);
    const fs::path parent = path.parent_path().filename();
    return parent.empty() ? path.filename().string() : (parent / path.filename()).string();
}

void gallery_picture(std::ostream& o, const GalleryPicture& p) {
    o << "<figure>";
    if (p.png.empty())
        o << "<div class=\"nopic\"></div>";
    else
        o << "<img alt=\"" << xml_escape(p.caption) << "\" src=\"" << p.png << "\">";
    o << "<figcaption>" << xml_escape(p.caption) << "</figcaption></figure>";
}

/// The misclassified queries: query, nearest view, nearest view of the true class.
void gallery_html(std::ostream& o, const std::vector<GalleryEntry>& gallery) {
    o << "<h2 id=\"misclassified\">Misclassified views</h2>\n<p>" << gallery.size()
      << " queries whose nearest view has another class: the query (blue, shaded by depth), "
         "the training view it was matched to, and the nearest view of its true class.</p>\n"
      << "<div class=\"gallery\">\n";
    for (const GalleryEntry& e : gallery) {
        o << "<div class=\"entry\"><div class=\"pictures\">";
        gallery_picture(o, e.query);
        gallery_picture(o, e.matched);
        gallery_picture(o, e.nearest_true);
        o << "</div><p><b>" << xml_escape(e.true_class) << "</b> seen as <b>"
          << xml_escape(e.predicted) << "</b> (rank "
          << (e.rank ? std::to_string(e.rank) : std::string("&gt; k")) << ")<br>"
          << xml_escape(short_path(e.file))
          << "<br>nearest: " << xml_escape(e.matched_view.empty() ? "-" : e.matched_view)
          << ", distance " << fixed_text(e.matched_distance, 4) << "<br>nearest "
          << xml_escape(e.true_class) << ": " << xml_escape(e.true_view.empty() ? "-" : e.true_view)
          << ", distance " << fixed_text(e.true_distance, 4);
        if (!e.note.empty()) o << "<br><span class=\"note\">" << xml_escape(e.note) << "</span>";
        o << "</p></div>\n";
    }
    o << "</div>\n";
}

}  // namespace

std::string report_html(const EvaluationReport& r, const ReportOptions& options) {
    const std::string k = std::to_string(r.k);
    std::ostringstream o;
    o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>"
      << xml_escape(options.title) << "</title>\n<style>\n"
      << "body{font-family:sans-serif;margin:2em;color:#222}\n"
      << "table{border-collapse:collapse;margin:1em 0}\n"
      << "th,td{border:1px solid #ccc;padding:3px 10px;text-align:right}\n"
      << "th{background:#f0f0f0}td.name,th.name{text-align:left}\n"
      << "tr.mean td{font-weight:bold;border-top:2px solid #888}\n"
      << ".gallery{display:flex;flex-wrap:wrap;gap:12px}\n"
      << ".entry{border:1px solid #ccc;padding:6px;font-size:12px}\n"
      << ".pictures{display:flex;gap:4px}figure{margin:0;text-align:center}\n"
      << "img{image-rendering:pixelated}.nopic{width:160px;height:120px;background:#f4f4f4}\n"
      << ".note{color:#a33}\n"
      << "</style>\n</head>\n<body>\n<h1>" << xml_escape(options.title) << "</h1>\n";
    o << "<table class=\"summary\">\n";
    auto row = [&](const std::string& name, const std::string& value) {
        o << "<tr><th class=\"name\">" << xml_escape(name) << "</th><td class=\"name\">"
          << xml_escape(value) << "</td></tr>\n";
    };
    row("mode", r.mode);
    if (!r.database.empty()) row("database", r.database);
    row(r.mode == "synthetic" ? "protocol" : "test set", r.test_set);
    row("descriptor", r.descriptor + (r.weighted ? " (learned weights)" : " (plain L1)"));
    row("k", k);
    row("samples", std::to_string(r.samples) + " evaluated, " + std::to_string(r.skipped) +
                       " skipped (class not in the database), " + std::to_string(r.failed) +
                       " failed");
    row("1-NN",
        percent_text(r.top1) + " % per sample, " + percent_text(r.class_top1) + " % per class");
    row(k + "-NN",
        percent_text(r.topk) + " % per sample, " + percent_text(r.class_topk) + " % per class");
    if (r.describe_ms > 0.0) row("describe", fixed_text(r.describe_ms, 2) + " ms per cloud");
    if (r.match_ms > 0.0) row("match", fixed_text(r.match_ms, 3) + " ms per query");
    row("time", fixed_text(r.total_seconds, 2) + " s on " + std::to_string(r.threads) + " threads");
    o << "</table>\n";

    o << "<h2>Per class</h2>\n<table class=\"classes\">\n<tr><th class=\"name\">class</th>"
      << "<th>samples</th><th>1-NN %</th><th>" << k << "-NN %</th>"
      << "<th class=\"name\">most confused with</th></tr>\n";
    for (const ClassMetrics& m : r.classes) {
        o << "<tr><td class=\"name\">" << xml_escape(m.class_name) << "</td><td>" << m.samples
          << (m.failed ? " (+" + std::to_string(m.failed) + " failed)" : "") << "</td><td>"
          << percent_text(m.top1) << "</td><td>" << percent_text(m.topk)
          << "</td><td class=\"name\">"
          << xml_escape(m.confused_with.empty()
                            ? std::string("-")
                            : m.confused_with + " (" + std::to_string(m.confused_count) + ")")
          << "</td></tr>\n";
    }
    o << "<tr class=\"mean\"><td class=\"name\">mean over classes</td><td>" << r.samples
      << "</td><td>" << percent_text(r.class_top1) << "</td><td>" << percent_text(r.class_topk)
      << "</td><td></td></tr>\n"
      << "<tr class=\"mean\"><td class=\"name\">per sample</td><td>" << r.samples << "</td><td>"
      << percent_text(r.top1) << "</td><td>" << percent_text(r.topk)
      << "</td><td></td></tr>\n</table>\n";

    if (!r.missing_classes.empty()) {
        o << "<h2>Skipped classes (not in the database)</h2>\n<ul>\n";
        for (const SkippedClass& s : r.missing_classes)
            o << "<li>" << xml_escape(s.class_name) << ": " << s.samples << "</li>\n";
        o << "</ul>\n";
    }
    o << "<h2>Rank curves</h2>\n" << rank_curves_svg(r, options);
    o << "<h2>Confusion matrix</h2>\n" << confusion_svg(r, options);
    if (!options.gallery.empty()) gallery_html(o, options.gallery);
    if (!r.failures.empty()) {
        o << "<h2>Failed queries</h2>\n<table>\n<tr><th class=\"name\">file</th>"
          << "<th class=\"name\">class</th><th class=\"name\">error</th></tr>\n";
        for (const QueryFailure& f : r.failures)
            o << "<tr><td class=\"name\">" << xml_escape(f.file) << "</td><td class=\"name\">"
              << xml_escape(f.true_class) << "</td><td class=\"name\">" << xml_escape(f.error)
              << "</td></tr>\n";
        o << "</table>\n";
    }
    o << "</body>\n</html>\n";
    return o.str();
}

ReportFiles write_report(const std::string& dir, const EvaluationReport& report,
                         const ReportOptions& options) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir))
        throw IoError(file_message(dir, 0, "cannot create the report folder: " + ec.message()));
    const fs::path base(dir);
    ReportFiles files;
    files.json = (base / "report.json").string();
    files.confusion_png = (base / "confusion.png").string();
    files.confusion_svg = (base / "confusion.svg").string();
    files.rank_curves_svg = (base / "rank_curves.svg").string();
    files.html = (base / "index.html").string();
    write_text(files.json, report_json(report, options));
    const std::vector<std::uint8_t> png = confusion_png(report, options);
    write_file(files.confusion_png, png.data(), png.size());
    write_text(files.confusion_svg, confusion_svg(report, options));
    write_text(files.rank_curves_svg, rank_curves_svg(report, options));
    write_text(files.html, report_html(report, options));
    return files;
}

}  // namespace esf
