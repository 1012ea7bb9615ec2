#include "esf/report/scene_page.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <span>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/convex_hull_2d.hpp"
#include "core/number_text.hpp"
#include "esf/core/error.hpp"
#include "esf/report/point_picture.hpp"
#include "report/markup.hpp"

namespace esf {

namespace {

namespace fs = std::filesystem;
using detail::xml_escape;

/// Outline colours, one per object (Tableau 10).
const std::array<const char*, 10> kColours = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                              "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                                              "#bcbd22", "#17becf"};

using detail::fixed_text;

using Pixel = std::array<long, 2>;

/// The convex hull of pixel positions (core/convex_hull_2d.hpp: counter-clockwise in pixel
/// coordinates, without collinear vertices). Pixel coordinates are small whole numbers, exact
/// as floats.
std::vector<Pixel> convex_hull(const std::vector<Pixel>& pixels) {
    std::vector<detail::Vec2> points;
    points.reserve(pixels.size());
    for (const Pixel& p : pixels)
        points.emplace_back(static_cast<float>(p[0]), static_cast<float>(p[1]));
    std::vector<Pixel> hull;
    for (const detail::Vec2& v : detail::monotone_chain(std::move(points)))
        hull.push_back({std::lround(v.x()), std::lround(v.y())});
    return hull;
}

std::string picture_uri(std::span<const Eigen::Vector3f> points, int width, int height,
                        std::uint8_t tint) {
    PointPictureOptions options;
    options.width = width;
    options.height = height;
    const std::vector<std::uint8_t> tints(points.size(), tint);
    return png_data_uri(picture_png(draw_points(points, options, tints)));
}

std::string object_label(std::size_t i, const RecognizedObject& o) {
    std::string label = std::to_string(i) + " ";
    if (!o.classified()) return label + "unclassified";
    return label + o.classification.class_name + " " + fixed_text(o.classification.confidence, 2);
}

const char* status_text(const RecognizedObject& o) {
    if (!o.classified()) return "failed";
    return to_string(o.cluster.status);
}

/// The convex hull of `points` projected into `frame` (empty when none projects).
std::vector<Pixel> projected_hull(std::span<const Eigen::Vector3f> points,
                                  const PointPicture& frame) {
    std::vector<Pixel> pixels;
    pixels.reserve(points.size());
    for (const Eigen::Vector3f& p : points)
        if (const auto uv = frame.projection.project(p))
            pixels.push_back({std::lround(uv->x()), std::lround(uv->y())});
    if (pixels.empty()) return {};
    return convex_hull(pixels);
}

/// A polygon's points attribute.
void svg_points(std::ostream& o, const std::vector<Pixel>& hull) {
    for (std::size_t n = 0; n < hull.size(); ++n)
        o << (n ? " " : "") << hull[n][0] << ',' << hull[n][1];
}

void frame_svg(std::ostream& o, const PointCloud& cloud, const SceneRecognition& scene,
               std::span<const MatchedView> views, const ScenePageOptions& options) {
    std::vector<std::uint8_t> tints(cloud.points.size(), kTintGrey);
    if (scene.plane_found)
        for (std::size_t i = 0; i < cloud.points.size(); ++i) {
            const Eigen::Vector3f& p = cloud.points[i];
            if (p.allFinite() && std::abs(scene.plane.height(p)) <= options.plane_distance)
                tints[i] = kTintTable;
        }
    PointPictureOptions picture_options;
    picture_options.width = options.frame_width;
    picture_options.height = options.frame_height;
    picture_options.margin = 2;
    const PointPicture frame = draw_points(cloud.points, picture_options, tints);
    const int w = frame.width, h = frame.height;
    o << "<svg class=\"frame\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << w << "\" height=\""
      << h << "\" viewBox=\"0 0 " << w << ' ' << h
      << "\" font-family=\"sans-serif\">\n<image width=\"" << w << "\" height=\"" << h
      << "\" href=\"" << png_data_uri(picture_png(frame)) << "\"/>\n";
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const RecognizedObject& object = scene.objects[i];
        const std::vector<Pixel> hull = projected_hull(object.cluster.points, frame);
        if (hull.empty()) continue;
        const char* colour = kColours[i % kColours.size()];
        if (i < views.size() && views[i].posed) {
            const std::vector<Pixel> fitted = projected_hull(views[i].points, frame);
            if (!fitted.empty()) {
                o << "<polygon class=\"fit\" fill=\"none\" stroke=\"" << colour
                  << "\" stroke-width=\"2\" stroke-dasharray=\"6,4\" points=\"";
                svg_points(o, fitted);
                o << "\"><title>" << xml_escape(object_label(i, object))
                  << ": the fitted model</title></polygon>\n";
            }
        }
        o << "<g class=\"object\"><title>" << xml_escape(object_label(i, object))
          << "</title><polygon fill=\"" << colour << "\" fill-opacity=\"0.15\" stroke=\"" << colour
          << "\" stroke-width=\"2\" points=\"";
        svg_points(o, hull);
        long top = h, left = w;
        for (const Pixel& p : hull) {
            top = std::min(top, p[1]);
            left = std::min(left, p[0]);
        }
        const long text_y = top > 16 ? top - 4 : top + 14;
        o << "\"/><text x=\"" << std::max(left, 2L) << "\" y=\"" << text_y
          << "\" font-size=\"13\" font-weight=\"bold\" fill=\"" << colour
          << "\" stroke=\"white\" stroke-width=\"3\" paint-order=\"stroke\">"
          << xml_escape(object_label(i, object)) << "</text></g>\n";
    }
    o << "</svg>\n";
}

void picture(std::ostream& o, const std::string& uri, const std::string& caption) {
    o << "<figure>";
    if (uri.empty())
        o << "<div class=\"nopic\"></div>";
    else
        o << "<img alt=\"" << xml_escape(caption) << "\" src=\"" << uri << "\">";
    o << "<figcaption>" << xml_escape(caption) << "</figcaption></figure>";
}

const char* kStyle =
    "body{font-family:sans-serif;margin:2em;color:#222}\n"
    "table{border-collapse:collapse;margin:1em 0}\n"
    "th,td{border:1px solid #ccc;padding:3px 10px;text-align:left;vertical-align:top}\n"
    "th{background:#f0f0f0}\n"
    ".pictures{display:flex;gap:6px}figure{margin:0;text-align:center;font-size:12px}\n"
    "img{image-rendering:pixelated}.nopic{width:160px;height:120px;background:#f4f4f4}\n"
    ".note{color:#a33}\n";

}  // namespace

std::string scene_page_html(const std::string& file, const PointCloud& cloud,
                            const SceneRecognition& scene, std::span<const MatchedView> views,
                            const ScenePageOptions& options) {
    if (!views.empty() && views.size() != scene.objects.size())
        throw std::invalid_argument("scene page: " + std::to_string(views.size()) +
                                    " matched views for " + std::to_string(scene.objects.size()) +
                                    " objects");
    std::ostringstream o;
    o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>"
      << xml_escape(options.title) << ": " << xml_escape(fs::path(file).filename().string())
      << "</title>\n<style>\n"
      << kStyle << "</style>\n</head>\n<body>\n<p><a href=\"index.html\">all scenes</a></p>\n<h1>"
      << xml_escape(fs::path(file).filename().string()) << "</h1>\n<p>" << xml_escape(file) << ": "
      << xml_escape(scene.message) << ". The frame shaded by depth (near = dark), the "
      << "table in green, each object outlined with its class and confidence (dashed: the "
      << "model fitted to it, where verification ran).</p>\n";
    frame_svg(o, cloud, scene, views, options);
    if (!scene.objects.empty())
        o << "<h2>Objects</h2>\n<table class=\"objects\">\n<tr><th>#</th><th>object and its "
             "nearest training view</th><th>class</th><th>confidence</th><th>model</th>"
             "<th>view</th><th>distance</th><th>points</th><th>status</th>"
             "<th>next best classes (votes)</th></tr>\n";
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const RecognizedObject& object = scene.objects[i];
        const Classification& c = object.classification;
        o << "<tr class=\"object\"><td>" << i << "</td><td><div class=\"pictures\">";
        picture(o,
                picture_uri(object.cluster.points, options.picture_width, options.picture_height,
                            kTintBlue),
                "object " + std::to_string(i));
        std::string note;
        if (!object.classified()) {
            note = object.error;
        } else if (views.empty() || views[i].points.empty()) {
            note = views.empty() ? "no training view drawn" : views[i].note;
            picture(o, "", "no picture");
        } else {
            picture(o,
                    picture_uri(views[i].points, options.picture_width, options.picture_height,
                                kTintGrey),
                    c.best_model + " #" + std::to_string(c.best_view));
        }
        o << "</div>";
        if (!note.empty()) o << "<span class=\"note\">" << xml_escape(note) << "</span>";
        o << "</td>";
        if (object.classified()) {
            o << "<td>" << xml_escape(c.class_name) << "</td><td>" << fixed_text(c.confidence, 2)
              << "</td><td>" << xml_escape(c.best_model) << "</td><td>" << c.best_view
              << "</td><td>" << fixed_text(c.best_distance, 4) << "</td>";
        } else {
            o << "<td>-</td><td>-</td><td>-</td><td>-</td><td>-</td>";
        }
        o << "<td>" << object.cluster.points.size() << "</td><td>" << status_text(object);
        if (!object.cluster.message.empty()) o << ": " << xml_escape(object.cluster.message);
        o << "</td><td>";
        for (std::size_t v = 1; v < c.votes.size(); ++v)
            o << (v > 1 ? ", " : "") << xml_escape(c.votes[v].class_name) << " ("
              << c.votes[v].votes << ")";
        if (c.votes.size() <= 1) o << "-";
        o << "</td></tr>\n";
    }
    if (!scene.objects.empty()) o << "</table>\n";
    o << "</body>\n</html>\n";
    return o.str();
}

std::string scene_index_html(std::span<const ScenePageLink> links, const std::string& title) {
    std::ostringstream o;
    o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>"
      << xml_escape(title) << "</title>\n<style>\n"
      << kStyle << "</style>\n</head>\n<body>\n<h1>" << xml_escape(title) << "</h1>\n"
      << "<table class=\"scenes\">\n<tr><th>scene</th><th>what was found</th><th>objects</th>"
         "</tr>\n";
    for (const ScenePageLink& l : links) {
        o << "<tr><td>";
        if (l.page.empty())
            o << xml_escape(l.file);
        else
            o << "<a href=\"" << xml_escape(l.page) << "\">" << xml_escape(l.file) << "</a>";
        o << "</td><td>";
        if (l.error.empty())
            o << xml_escape(l.message);
        else
            o << "<span class=\"note\">" << xml_escape(l.error) << "</span>";
        o << "</td><td>";
        for (std::size_t i = 0; i < l.classes.size(); ++i)
            o << (i ? ", " : "") << xml_escape(l.classes[i]);
        o << "</td></tr>\n";
    }
    o << "</table>\n</body>\n</html>\n";
    return o.str();
}

std::string write_page(const std::string& dir, const std::string& name, const std::string& text) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir))
        throw IoError(file_message(dir, 0, "cannot create the report folder: " + ec.message()));
    const fs::path path = fs::path(dir) / name;
    detail::write_file_atomically(path, text.data(), text.size());
    return path.string();
}

}  // namespace esf
