#pragma once
// A page per recognised table scene, for people checking the recognizer at a glance:
//
//   the frame   the scene's points drawn as a depth-shaded picture (esf/point_picture.hpp), the
//               table plane's points in green, each object outlined (the convex hull of its
//               points in the picture) and labelled with its number, class and confidence as
//               SVG text over the picture; where verification fitted a model to the object,
//               the outline of the posed model's visible surface, dashed, in the same colour
//   per object  its cluster drawn on its own next to the nearest training view of its class
//               (the view's points, see esf/view_pictures.hpp), with model, view, distance,
//               points, status and the next best classes of the vote
//
// Pages are self-contained HTML (pictures as PNG data URIs, no script, no link out) and depend
// only on their inputs, so equal inputs give equal pages. scene_index_html() links the pages.

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "esf/core/point_cloud.hpp"
#include "esf/recognition/recognizer.hpp"

namespace esf {

/// The nearest training view of an object, as drawn next to it: its points in its camera frame,
/// or none with a note saying why.
struct MatchedView {
    Points points;
    std::string note;
    /// The points are the model fitted to the object (Classification::fit: the pose is the
    /// model aligned to the points), in the scene's camera frame: the frame outlines them too.
    bool posed = false;
};

struct ScenePageOptions {
    std::string title = "esf scene";
    int frame_width = 480;  ///< the frame picture (pixels)
    int frame_height = 360;
    int picture_width = 160;  ///< an object's pictures
    int picture_height = 120;
    /// Points within this distance of the plane (m) are shaded as the table.
    float plane_distance = 0.01f;
};

/// The page of one scene: `file` names it, `cloud` is what was segmented (its points in the
/// sensor frame, +z forward), `views` is empty or holds one MatchedView per object of `scene`.
/// Throws std::invalid_argument when `views` has another size or a picture size is below 1.
std::string scene_page_html(const std::string& file, const PointCloud& cloud,
                            const SceneRecognition& scene, std::span<const MatchedView> views,
                            const ScenePageOptions& options = {});

/// One line of the index: the page (a relative link), the scene file and what was found.
struct ScenePageLink {
    std::string page;
    std::string file;
    std::string message;
    std::vector<std::string> classes;  ///< per object, "-" when it has none
    std::string error;                 ///< non-empty: the scene failed, no page
};

std::string scene_index_html(std::span<const ScenePageLink> links, const std::string& title);

/// Writes `text` to dir / name (dir created with its parents when missing) through a temporary
/// file and a rename; returns the path. Throws esf::IoError naming the folder or the file.
std::string write_page(const std::string& dir, const std::string& name, const std::string& text);

}  // namespace esf
