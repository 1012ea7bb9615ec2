#pragma once
// Generated cluttered table scenes: the proving ground for segmentation and recognition on data
// that no rule was chosen on. Meshes are placed on a table (standing, lying, stacked, touching,
// leaning, hiding one another), sometimes near the table's edge or against a wall, and seen by a
// Kinect-like sensor from 0.6 to 1.5 m, 25 to 65 degrees above the table. Every frame comes with
// its truth: per-pixel labels in the Object Segmentation Database's convention and each object's
// model, pose and visible share.
//
// A scene depends only on (seed, scene index) and the models given, never on the thread count or
// on which other scenes are composed.

#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "esf/core/camera.hpp"
#include "esf/core/enum_names.hpp"
#include "esf/core/point_cloud.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/render/sensor_model.hpp"

namespace esf {

/// The kinds of table scene, like the Object Segmentation Database's and harder:
///   isolated   2-4 objects standing apart (3-15 cm gaps)
///   touching   2-5 objects, each touching another (0-4 mm gaps)
///   stacked    boxes on boxes and things on boxes, beside 0-2 other objects
///   occluded   2-4 objects, each after the first partly hiding one behind it
///   cylindric  2-5 round objects (cans, cups, bottles: a round footprint), apart or touching
///   mixed      5-7 objects of any kind, half of them touching another
///   complex    10-18 objects, touching, some leaning on their neighbours
enum class ClutterType { kIsolated, kTouching, kStacked, kOccluded, kCylindric, kMixed, kComplex };

/// "isolated", "touching", ... (to_string, parse_enum<ClutterType>), in the order above.
template <>
struct EnumNames<ClutterType> {
    static constexpr const char* what = "scene type";
    static constexpr std::array<EnumName<ClutterType>, 7> table{
        {{ClutterType::kIsolated, "isolated"},
         {ClutterType::kTouching, "touching"},
         {ClutterType::kStacked, "stacked"},
         {ClutterType::kOccluded, "occluded"},
         {ClutterType::kCylindric, "cylindric"},
         {ClutterType::kMixed, "mixed"},
         {ClutterType::kComplex, "complex"}}};
};

/// Every type, in the order above.
inline const std::vector<ClutterType>& clutter_types() {
    static const std::vector<ClutterType> types = [] {
        std::vector<ClutterType> all;
        for (const EnumName<ClutterType>& entry : EnumNames<ClutterType>::table)
            all.push_back(entry.value);
        return all;
    }();
    return types;
}

/// A model that scenes may hold: a mesh in metres, +z up (as training assumes), standing on its
/// lowest point when upright.
struct ClutterModel {
    Mesh mesh;             ///< metres (the file's coordinates times `scale`)
    std::string category;  ///< the class it is evaluated as
    std::string file;      ///< the caller's name for it (truth.json: relative to the root)
    double scale = 1.0;    ///< file units -> metres, already applied to `mesh`
};

inline constexpr double kClutterMinDistance = 0.6;    ///< metres, camera to the scene's centre
inline constexpr double kClutterMaxDistance = 1.5;    ///< metres
inline constexpr double kClutterMinElevation = 25.0;  ///< degrees above the table
inline constexpr double kClutterMaxElevation = 65.0;  ///< degrees
inline constexpr double kClutterMaxSizeSpread = 1.0;  ///< ClutterOptions::size_spread's largest
/// Height of the floor below the table top (metres), seen past a table edge.
inline constexpr double kClutterTableHeight = 0.74;
/// Object labels are kClutterLabelDivisor * id with ids from kClutterFirstObjectId, as in the
/// Object Segmentation Database (label / 10 = object id; 1 = table, 0 = no return or
/// background: floor, wall, and objects with fewer than kClutterMinLabelledPixels pixels).
inline constexpr std::uint32_t kClutterLabelDivisor = 10;
inline constexpr std::uint32_t kClutterFirstObjectId = 2;
inline constexpr std::uint32_t kClutterTableLabel = 1;
inline constexpr std::size_t kClutterMinLabelledPixels = 100;

struct ClutterOptions {
    CameraIntrinsics camera = CameraIntrinsics::kinect();
    SensorNoise noise = SensorNoise::kKinect;
    double min_distance = kClutterMinDistance;
    double max_distance = kClutterMaxDistance;
    double min_elevation = kClutterMinElevation;
    double max_elevation = kClutterMaxElevation;
    /// Share of scenes with a wall behind the objects, and with a table edge near them.
    double wall_share = 0.25;
    double edge_share = 0.3;
    /// Objects other than their models' sizes: each placed object is its model scaled by a
    /// factor drawn log-uniformly from [1 / (1 + size_spread), 1 + size_spread], as real
    /// instances of a category are larger or smaller than the models of it a database holds.
    /// 0 (the default): every object at its model's size. Within [0, kClutterMaxSizeSpread].
    double size_spread = 0.0;
    /// Scene i is of type types[i % types.size()]; empty: every type in turn.
    std::vector<ClutterType> types;
    std::uint64_t seed = 0;
};

/// One object of a composed scene.
struct ClutterObject {
    std::size_t model = 0;        ///< index into the composer's models
    std::uint32_t object_id = 0;  ///< label / kClutterLabelDivisor; kClutterFirstObjectId + index
    /// Mesh file coordinates -> camera (metres), scale included: the upper-left 3x3 block is
    /// scale * rotation (the model's file units -> metres times the object's size).
    Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
    /// The object's size against its model's (1 unless ClutterOptions::size_spread > 0).
    double size = 1.0;
    /// Share of the object's pixels (seen alone from the same camera, without noise) that the
    /// scene shows (without noise): 0 when hidden or out of view.
    double visible = 0.0;
    std::size_t pixels = 0;  ///< pixels labelled as the object in the frame (with noise)
    bool labelled = false;   ///< pixels >= kClutterMinLabelledPixels (else labelled 0)
    /// How it stands: "standing", "lying", "stacked" (on another object), "leaning".
    std::string placement;
};

struct ClutterScene {
    ClutterType type = ClutterType::kIsolated;
    /// Organised width x height frame, camera coordinates (NaN where no return), with labels
    /// (above) and flat colours per surface.
    PointCloud cloud;
    Eigen::Isometry3d world_to_camera = Eigen::Isometry3d::Identity();  ///< world: table z = 0
    std::vector<ClutterObject> objects;
    bool wall = false;
    bool table_edge = false;
};

/// Composes scenes of a fixed set of models. compose() is const and may run on several threads
/// at once; each call renders on the calling thread only.
class ClutterComposer {
  public:
    /// Throws std::invalid_argument for no models, a bad mesh (check_mesh) or bad options.
    ClutterComposer(std::vector<ClutterModel> models, ClutterOptions options);
    ~ClutterComposer();
    ClutterComposer(ClutterComposer&&) noexcept;
    ClutterComposer& operator=(ClutterComposer&&) noexcept;

    /// Scene `index` of the seed (its type: options().types, above). When the models lack a
    /// kind the type needs (no round model for cylindric, no box for stacked), any model stands
    /// in.
    ClutterScene compose(std::size_t index) const;
    ClutterType type_of(std::size_t index) const;

    const std::vector<ClutterModel>& models() const;
    const ClutterOptions& options() const;
    /// Whether model i has a round footprint (used for cylindric scenes) or is box-like (a
    /// rectangular footprint and a flat top: a base for stacking).
    bool round(std::size_t model) const;
    bool boxy(std::size_t model) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace esf
