#pragma once
// Hypothesis verification: a candidate model aligned to the points the sensor saw, and scored.
//
//   start   the matched training view's rotation, turned towards the object's direction from the
//           camera, the model's visible surface centred on the object's points
//   align   point-to-plane ICP (the model's normals) of the model's camera-facing surface samples
//           to their nearest object points (a grid of cells, recognition/nearest_points.hpp),
//           correspondences within a radius shrinking from 3 to 1 cm
//   score   inliers: share of the object's points within `inlier_distance` of the posed surface
//           (the model's grid, built once per model: PreparedModel);
//           support: share of the posed model's visible surface (not hidden by nearer returns)
//           with object points on it;
//           violations: share of the posed visible surface where the sensor sees free space:
//           with the frame, a return farther than the model by `violation_margin` at the pixel a
//           model point projects to; without a frame (a lone cloud), a pixel outside the object's
//           own outline (its points projected with the camera, 2 pixels of slack)
//
// A hypothesis is verified when inliers >= min_inliers and violations <= max_violations. The
// same inputs give the same result on any thread.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>

#include "esf/core/camera.hpp"
#include "esf/core/point_cloud.hpp"
#include "esf/mesh/model_surface.hpp"

namespace esf {

struct FitScore {
    double inliers = 0.0;     ///< share of the object's points explained, [0, 1]
    double violations = 0.0;  ///< share of the visible model surface in seen free space, [0, 1]
    double support = 0.0;     ///< share of the visible, unhidden model surface on object points
    double rms_mm = 0.0;      ///< RMS distance of the inlier points, millimetres
    /// Agreement both ways, less what the sensor saw through.
    double score() const { return 0.5 * (inliers + support) - violations; }
};

struct VerificationOptions {
    std::size_t candidates = 3;  ///< distinct models tried, nearest first (>= 1)
    /// true: models of any class, and the best fit names the class too; false: the candidates
    /// are models of the class the neighbours named, and verification picks the model and pose
    /// (BENCHMARKS.md, "Verification": deciding the class is the more accurate on real data).
    bool decide_class = true;
    /// Candidates are fitted nearest first; a verified fit whose score() reaches this ends the
    /// search (the farther candidates are not fitted). Above 1 (no fit scores more, the
    /// default): every candidate. 0.7 saves a fifth to a quarter of the time and costs a few
    /// cans named box on real views (BENCHMARKS.md).
    double accept_score = 2.0;
    /// An object's fit from an earlier frame (a track's, PriorFit) is fitted first, from where it
    /// stood; verified again with a score at most this much below its former one, it is kept and
    /// no other candidate is fitted (>= 0).
    double prior_tolerance = 0.1;
    /// The candidates are compared by their fit's score() less this times the distance between
    /// the object's cylinder-box contrast and the mean contrast of the candidate's training views
    /// (descriptors with that block, primitive_fit.hpp): a box fitted inside a can's front loses
    /// to a can model that fits about as well (BENCHMARKS.md, "Shape agreement"). In [0, 2]; 0:
    /// the score alone. The chosen fit's own score is reported unchanged.
    double shape_weight = 0.25;
    /// true: every model's size is fitted (within [0.8, 1.25]) while the candidates compete, as
    /// objects are larger or smaller than the database's models of their class; the chosen fit
    /// of a model whose size is known (metric in the catalog) is then fitted again at that
    /// size, from where it stood, so that its pose and fit are the model's own (BENCHMARKS.md,
    /// "Every model's size free"). false: only the size of a model whose size the catalog
    /// guesses is fitted.
    bool every_size_free = true;
    /// Among the fits of the class the best fit names, the model is the one with the highest
    /// compared score less this times |ln(fitted size)|: of look-alike models (a small and a
    /// large bottle of one make), the one that needs the least resizing names the model and
    /// pose. The class is not changed (BENCHMARKS.md, "Look-alike models"). In [0, 10]; 0: the
    /// compared score alone.
    double resize_weight = 1.0;
    /// ICP pairs each camera-facing model sample with its nearest object point; true: also each
    /// object point with its nearest camera-facing model sample, so that the model covers the
    /// object as well as lying on it, and a free size does not shrink where the object is cut.
    /// Where the database holds the objects' own models, poses and sizes come out better
    /// (generated tables of those models: 4 % more poses within ADD-S 0.1 d, more objects found
    /// and named right on every generated table); the real scenes and views do not gain (two
    /// fewer named right a training seed, within the noise), and verification costs 1.8 -> 2.9
    /// ms an object (BENCHMARKS.md, "Two-way ICP"). false: model samples only.
    bool two_way = false;
    int iterations = 10;                ///< ICP iterations (>= 1)
    std::size_t surface_points = 2000;  ///< samples of each model's surface
    double inlier_distance = 0.004;     ///< metres
    double violation_margin = 0.015;    ///< metres
    double min_inliers = 0.5;
    double max_violations = 0.25;
    CameraIntrinsics camera = CameraIntrinsics::kinect();  ///< for lone clouds (no frame)
};

/// Throws std::invalid_argument naming the option that is out of range.
void validate(const VerificationOptions& options);

/// What the model is checked against: the object's finite points and, when known, the organised
/// frame they were segmented from (camera coordinates, the frame's intrinsics in `camera`).
struct Observation {
    std::span<const Eigen::Vector3f> points;
    const PointCloud* frame = nullptr;
};

struct PoseFit {
    /// Model (metres, ModelSurface frame) -> camera: a rigid motion, times `scale` where the
    /// scale was free.
    Eigen::Matrix4d model_to_camera = Eigen::Matrix4d::Identity();
    double scale = 1.0;  ///< found for the model (1 when not free), in [0.8, 1.25]
    FitScore fit;
    bool verified = false;
    /// The score could not exceed the `must_beat` it was given: scoring stopped as soon as that
    /// was sure, so `fit` may be incomplete, and the hypothesis loses (never with the default,
    /// which every score beats).
    bool abandoned = false;
};

class PreparedModel;

/// Where a fit starts from.
enum class FitStart {
    /// A training view's pose (model -> the training camera, which looked at the model's centre):
    /// its rotation turned towards the object's direction from the camera.
    kTrainingView,
    /// A pose in this camera (an earlier fit of the same object): its rotation as it is.
    kCameraPose,
};

/// An observation made ready for several hypotheses: its search grid and what the sensor saw
/// (the frame, or the object's outline) are built once. The observation's points and frame
/// must outlive it. Throws std::invalid_argument for fewer than 3 points or a frame that is not
/// an organised cloud of the camera's size.
class PreparedObservation {
  public:
    PreparedObservation(const Observation& observation, const CameraIntrinsics& camera);
    ~PreparedObservation();
    PreparedObservation(PreparedObservation&&) noexcept;
    PreparedObservation& operator=(PreparedObservation&&) noexcept;

  private:
    friend PoseFit fit_model(const PreparedModel&, const Eigen::Matrix4d&,
                             const PreparedObservation&, const VerificationOptions&, bool, FitStart,
                             double);
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// A model's surface made ready for several hypotheses: its search grid (model frame) is built
/// once. Throws std::invalid_argument for a surface check_model_surface() refuses (empty, normals
/// that do not match its points, values that are not finite).
class PreparedModel {
  public:
    explicit PreparedModel(ModelSurface surface);
    ~PreparedModel();
    PreparedModel(PreparedModel&&) noexcept;
    PreparedModel& operator=(PreparedModel&&) noexcept;
    const ModelSurface& surface() const;

  private:
    friend PoseFit fit_model(const PreparedModel&, const Eigen::Matrix4d&,
                             const PreparedObservation&, const VerificationOptions&, bool, FitStart,
                             double);
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// Aligns `surface` to the observation from the rotation of `view_pose` (model -> the training
/// camera; its scale, if any, is removed) and scores the result. With `free_scale`, the model's
/// size is fitted too, within [0.8, 1.25] of the surface's. Throws
/// std::invalid_argument for fewer than 3 observed points, a frame that is not organised or not of
/// the camera's size, bad options or a non-finite pose.
PoseFit fit_model(const ModelSurface& surface, const Eigen::Matrix4d& view_pose,
                  const Observation& observation, const VerificationOptions& options,
                  bool free_scale = false);
/// The same against a prepared observation (prepared with options.camera).
PoseFit fit_model(const ModelSurface& surface, const Eigen::Matrix4d& view_pose,
                  const PreparedObservation& observation, const VerificationOptions& options,
                  bool free_scale = false);
/// The same with a prepared model: what a recognizer uses for many objects. With
/// FitStart::kCameraPose, `view_pose` is a pose in this camera (an earlier fit of the object)
/// and its rotation is kept as it is; either way the start is centred on the object's points.
/// A hypothesis that must beat another: once its score() is sure to end at or below
/// `must_beat`, scoring stops and the fit comes back `abandoned` (the same answer, sooner: the
/// score's parts are counted a point at a time, and bounded by what the rest could add).
PoseFit fit_model(const PreparedModel& model, const Eigen::Matrix4d& view_pose,
                  const PreparedObservation& observation, const VerificationOptions& options,
                  bool free_scale = false, FitStart start = FitStart::kTrainingView,
                  double must_beat = -std::numeric_limits<double>::infinity());

}  // namespace esf
