#pragma once
// Pictures of training views for report pages. The database keeps a view's pose but not its
// points, so a view is drawn by rendering its model's mesh again from that pose (no sensor
// noise): the model's file is found under the training root the database was trained from.
//
//   ViewRenderer       category, model, pose -> the view's points in its camera frame
//   misclassified_gallery   the queries of an evaluation whose nearest view has another class,
//                      each with its nearest view and the nearest view of its true class
//
// Not thread-safe: a ViewRenderer caches the meshes it has loaded. No output, no global state.

#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "esf/core/point_cloud.hpp"
#include "esf/evaluation/evaluation.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/render/render.hpp"
#include "esf/report/report.hpp"
#include "esf/training/database.hpp"

namespace esf {

class ViewRenderer {
  public:
    /// Reads the models (category, name, file) of the database; meshes are loaded from
    /// `mesh_root` / file when first drawn. Throws esf::IoError naming the database when it
    /// cannot be read.
    ViewRenderer(const std::string& database, const std::string& mesh_root,
                 const CameraIntrinsics& camera = CameraIntrinsics::kinect());
    ~ViewRenderer();
    ViewRenderer(ViewRenderer&&) noexcept;
    ViewRenderer& operator=(ViewRenderer&&) noexcept;

    /// The visible surface of the model seen from `pose` (model file coordinates -> camera, the
    /// upper-left block scale * rotation, as the database stores it), in the camera frame.
    /// Throws std::invalid_argument naming the model when the database has no such model,
    /// esf::IoError naming the mesh file when it cannot be loaded.
    Points render(const std::string& category, const std::string& model,
                  const Eigen::Matrix4f& pose);

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

struct GalleryOptions {
    std::size_t per_class = 0;  ///< at most this many queries per true class; 0 = all
    int width = 160;            ///< picture size (pixels)
    int height = 120;
    /// Draws the training views; null: the entries have no view pictures.
    ViewRenderer* views = nullptr;
};

/// The gallery of misclassified queries of a test-set evaluation (report.queries whose
/// predicted class is not the true class, in report order): each query is read and described
/// again with `recognizer`, its nearest view overall and the nearest view of its true class
/// are found among all views, and the query and both views are drawn. A query that cannot be
/// read again, or a view that cannot be drawn, keeps its entry with a note saying why.
std::vector<GalleryEntry> misclassified_gallery(const Recognizer& recognizer,
                                                const EvaluationReport& report,
                                                const GalleryOptions& options = {});

}  // namespace esf
