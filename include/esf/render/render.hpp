#pragma once
// Synthetic partial views of a mesh (the paper's training data, Sec. IV): cameras on a
// tessellated view sphere, depth rendered by ray casting (Embree, CPU only, no display),
// optional Kinect-like sensor model; and depth frames of whole scenes (meshes on a table).
//
// Both faces of every triangle are hit (no back-face culling): scanned meshes often have
// inward-facing triangles or open zero-thickness shells. Results are deterministic for a given
// seed, whatever the thread count.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "esf/core/camera.hpp"
#include "esf/core/point_cloud.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/render/sensor_model.hpp"

namespace esf {

struct RenderOptions {
    int level = 1;  ///< view sphere subdivisions: 0 = 20 views, 1 = 80 (paper), 2 = 320
    CameraIntrinsics camera = CameraIntrinsics::kinect();
    /// Fraction of the smaller image side that the model's bounding sphere (around its bounding
    /// box centre) spans; sets the camera distance. Must be positive.
    double fill_fraction = 0.5;
    /// When set, the camera distance (metres, from the model's centre) instead of fill_fraction;
    /// must exceed the bounding sphere radius.
    std::optional<double> distance;
    /// When set with `distance` and above it, each view's camera distance is drawn uniformly
    /// from [distance, max_distance], seeded by (seed, view index): real table scenes are taken
    /// from 0.6 to 1.2 m. Otherwise every view is seen from `distance` (or fill_fraction). Must
    /// be positive and finite when set.
    std::optional<double> max_distance;
    /// Cameras kept from the view sphere: those whose elevation (degrees, the angle between the
    /// direction from the model's centre to the camera and the model's xy plane, positive
    /// towards +z) lies in [min_elevation, max_elevation]. The default keeps the whole sphere;
    /// [15, 75] keeps the cameras that see an upright model standing on a table from where a
    /// robot or a person looks at it.
    double min_elevation = -90.0;
    double max_elevation = 90.0;
    SensorNoise noise = SensorNoise::kKinect;  ///< see sensor_model.hpp
    std::uint64_t seed = 0;                    ///< noise seed; view i draws from (seed, i)
    /// Uniform factor applied to the file coordinates before rendering, so that they are metres
    /// (e.g. 0.001 for a millimetre file). The Kinect model is only meaningful at metric size.
    double scale = 1.0;
    /// When set, overrides `scale`: the model is scaled so that the longest side of its
    /// axis-aligned bounding box is this many metres (e.g. for KIT meshes, stored with a middle
    /// side of 45 mm whatever their real size).
    std::optional<double> target_extent;
    int threads = 0;  ///< for render_views: 0 = all cores
};

/// One synthetic view: the visible surface in the camera frame and the model -> camera pose.
struct RenderedView {
    int index = 0;  ///< view sphere index
    Points points;  ///< camera frame, metres, in pixel order (row by row)
    /// Maps model (file) coordinates to camera coordinates. When the model is rescaled
    /// (RenderOptions::scale / target_extent), the upper-left 3x3 block is scale * rotation.
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
};

/// The Embree scene of one mesh, built once and used for every view. render_view() is const and
/// may be called from several threads at once. Only the pixels inside the projection of the
/// model's bounding sphere are cast, in packets of rays.
class MeshRenderer {
  public:
    /// Throws std::invalid_argument for a bad mesh (check_mesh), a mesh of zero extent or bad
    /// options.
    MeshRenderer(const Mesh& mesh, const RenderOptions& options);
    ~MeshRenderer();
    MeshRenderer(MeshRenderer&&) noexcept;
    MeshRenderer& operator=(MeshRenderer&&) noexcept;

    std::size_t view_count() const;  ///< cameras kept (see RenderOptions::min_elevation)
    /// View sphere index of kept camera `index`. Throws std::invalid_argument past view_count().
    int view_index(std::size_t index) const;
    /// Renders view `index` (0 .. view_count() - 1, the kept cameras in view sphere order): the
    /// camera sits at centre + distance * view_sphere(level)[view_index(index)] (in scaled model
    /// coordinates) and looks at the centre, image up = model +z (see look_at); the distance is
    /// camera_distance(), or drawn from [camera_distance(), max_distance]. The result's index is
    /// the view sphere index. Throws std::invalid_argument past view_count().
    RenderedView render_view(std::size_t index) const;
    /// Renders the model from any camera: `scaled_model_to_camera` is the rigid motion from the
    /// model's file coordinates times scale() (metres) to the camera. The sensor noise is keyed
    /// by (options().seed, `noise_key`); render_view(i) uses key i.
    Points render_pose(const Eigen::Isometry3d& scaled_model_to_camera,
                       std::uint64_t noise_key) const;

    double scale() const;            ///< file units -> metres factor in use
    Eigen::Vector3d centre() const;  ///< bounding box centre, file units
    double radius() const;           ///< bounding sphere radius around centre(), metres
    double camera_distance() const;  ///< metres from the centre
    const RenderOptions& options() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// Renders all views of a mesh (views in index order; a view may have few or no points), on
/// `options.threads` threads, one view per task.
std::vector<RenderedView> render_views(const Mesh& mesh, const RenderOptions& options);

/// A mesh placed in a scene. `mesh` must outlive the render_scene() call.
struct SceneObject {
    const Mesh* mesh = nullptr;
    Eigen::Isometry3d model_to_world = Eigen::Isometry3d::Identity();  ///< metres
};

inline constexpr std::uint32_t kSceneLabelNone = 0;   ///< pixel without return
inline constexpr std::uint32_t kSceneLabelTable = 1;  ///< the table plane
/// Label of the pixels showing objects[i]: kSceneLabelFirstObject + i.
inline constexpr std::uint32_t kSceneLabelFirstObject = 2;

struct SceneOptions {
    CameraIntrinsics camera = CameraIntrinsics::kinect();
    SensorNoise noise = SensorNoise::kNone;
    std::uint64_t seed = 0;
    /// Adds the plane z = 0 of the world frame (world +z up), both faces, as the table the
    /// objects stand on.
    bool table_plane = false;
    /// The table covers |x|, |y| <= table_half_size (metres); infinity = an infinite plane.
    double table_half_size = std::numeric_limits<double>::infinity();
    /// Returns farther than this (camera z, metres) are dropped, as by a sensor's range.
    double max_depth = std::numeric_limits<double>::infinity();
    int threads = 0;  ///< 0 = all cores
};

/// Renders one depth frame of meshes (and optionally a table plane) seen from a camera:
/// an organised cloud of width x height points in the camera frame (NaN where no return) with
/// one label per pixel (kSceneLabelNone, kSceneLabelTable or kSceneLabelFirstObject + object
/// index). Throws std::invalid_argument for a null or bad mesh or bad options.
PointCloud render_scene(std::span<const SceneObject> objects,
                        const Eigen::Isometry3d& world_to_camera, const SceneOptions& options);

}  // namespace esf
