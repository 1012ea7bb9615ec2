// Hypothesis verification (esf/recognition/pose_verification.hpp): ICP of a model's visible
// surface to an object's points, and the fit's score against the frame.

#include "esf/recognition/pose_verification.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "recognition/nearest_points.hpp"

namespace esf {

using detail::NearestPoints;

namespace {

constexpr std::size_t kNoMatch = std::numeric_limits<std::size_t>::max();  // no point (hint)

// At most `limit` of `points`, evenly strided (deterministic).
Points stride_sample(std::span<const Eigen::Vector3f> points, std::size_t limit) {
    Points out;
    if (points.size() <= limit) {
        out.assign(points.begin(), points.end());
        return out;
    }
    out.reserve(limit);
    for (std::size_t i = 0; i < limit; ++i) out.push_back(points[i * points.size() / limit]);
    return out;
}

// The rotation that turns the camera's optical axis (0, 0, 1) towards `direction`.
Eigen::Matrix3d towards(const Eigen::Vector3d& direction) {
    return Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), direction.normalized())
        .toRotationMatrix();
}

Eigen::Matrix4d exp_se3(const Eigen::Matrix<double, 6, 1>& x) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    const Eigen::Vector3d w = x.head<3>();
    const double angle = w.norm();
    if (angle > 1e-12)
        m.topLeftCorner<3, 3>() = Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
    m.topRightCorner<3, 1>() = x.tail<3>();
    return m;
}

// Where the sensor looked: the frame's depth per pixel, or the object's own outline.
class SeenSpace {
  public:
    SeenSpace(const Observation& o, const CameraIntrinsics& camera) : camera_(camera) {
        width_ = static_cast<std::size_t>(camera.width);
        height_ = static_cast<std::size_t>(camera.height);
        frame_ = o.frame;
        if (frame_ != nullptr) return;
        // The outline: pixels the object's points fall on, grown by kSlack pixels. Kept as the
        // running sums of the points per pixel (a summed-area table) over the box of the image
        // the outline lies in, so that a pixel's square of slack is four reads.
        std::vector<std::pair<long, long>> hits;  // (u, v)
        hits.reserve(o.points.size());
        long u_min = std::numeric_limits<long>::max(), v_min = u_min, u_max = -1, v_max = -1;
        for (const Eigen::Vector3f& p : o.points) {
            long u = 0, v = 0;
            if (!project(p.cast<double>(), u, v)) continue;
            u_min = std::min(u_min, u);
            u_max = std::max(u_max, u);
            v_min = std::min(v_min, v);
            v_max = std::max(v_max, v);
            hits.emplace_back(u, v);
        }
        if (hits.empty()) return;
        box_u_ = std::max(0L, u_min - kSlack);
        box_v_ = std::max(0L, v_min - kSlack);
        box_width_ = std::min(static_cast<long>(width_) - 1, u_max + kSlack) - box_u_ + 1;
        box_height_ = std::min(static_cast<long>(height_) - 1, v_max + kSlack) - box_v_ + 1;
        // sums_[(v + 1) * stride + u + 1]: the points on the box's pixels up to (u, v).
        const std::size_t stride = static_cast<std::size_t>(box_width_) + 1;
        sums_.assign(stride * (static_cast<std::size_t>(box_height_) + 1), 0);
        for (const auto& [u, v] : hits)
            ++sums_[static_cast<std::size_t>(v - box_v_ + 1) * stride +
                    static_cast<std::size_t>(u - box_u_ + 1)];
        for (std::size_t v = 1; v <= static_cast<std::size_t>(box_height_); ++v)
            for (std::size_t u = 1; u < stride; ++u)
                sums_[v * stride + u] += sums_[v * stride + u - 1] + sums_[(v - 1) * stride + u] -
                                         sums_[(v - 1) * stride + u - 1];
    }

    // What the sensor saw at a model point, its pixel found once.
    struct Look {
        int violation = -1;   // 1: the sensor saw through the point; 0: consistent; -1: unknown
        bool hidden = false;  // something nearer than the point (by the margin) hides it
    };
    Look look(const Eigen::Vector3d& p, double margin) const {
        long u = 0, v = 0;
        if (!project(p, u, v)) return Look{.violation = -1, .hidden = frame_ != nullptr};
        if (frame_ == nullptr)
            return Look{.violation = on_outline(u - box_u_, v - box_v_) ? 0 : 1, .hidden = false};
        const double seen =
            frame_->points[static_cast<std::size_t>(v) * width_ + static_cast<std::size_t>(u)].z();
        if (!std::isfinite(seen)) return Look{.violation = -1, .hidden = true};
        return Look{.violation = seen > p.z() + margin ? 1 : 0, .hidden = seen < p.z() - margin};
    }

  private:
    static constexpr long kSlack = 2;

    // Whether a point falls within kSlack pixels of the box's pixel (u, v). The box holds
    // every such pixel, so a pixel outside it has none.
    bool on_outline(long u, long v) const {
        if (u < 0 || v < 0 || u >= box_width_ || v >= box_height_) return false;
        const auto at = [&](long x, long y) {  // the sum over [0, x) x [0, y)
            return sums_[static_cast<std::size_t>(y * (box_width_ + 1) + x)];
        };
        const long u0 = std::max(0L, u - kSlack), u1 = std::min(box_width_, u + kSlack + 1);
        const long v0 = std::max(0L, v - kSlack), v1 = std::min(box_height_, v + kSlack + 1);
        return at(u1, v1) - at(u0, v1) - at(u1, v0) + at(u0, v0) > 0;
    }

    bool project(const Eigen::Vector3d& p, long& u, long& v) const {
        return p.z() > 1e-6 && camera_.pixel(p.x(), p.y(), p.z(), u, v);
    }

    CameraIntrinsics camera_;
    std::size_t width_ = 0, height_ = 0;
    const PointCloud* frame_ = nullptr;
    long box_u_ = 0, box_v_ = 0, box_width_ = 0, box_height_ = 0;  // the outline's box
    std::vector<std::uint32_t> sums_;  // points per pixel of the box, summed (on_outline)
};

constexpr std::size_t kIcpSamples = 200;      // visible surface samples per ICP iteration
constexpr std::size_t kObjectSamples = 1000;  // object points in the search grid and the score
constexpr double kPointWeight = 0.1;          // of the point-to-point term in ICP
constexpr double kMinScale = 0.8;             // bounds of a free scale, relative to the model's
constexpr double kMaxScale = 1.25;
constexpr std::size_t kBoundEvery = 32;  // points counted between two checks of a score's bound
constexpr double kBoundSlack = 1e-9;     // below must_beat by more than rounding could explain
constexpr float kObjectCell = 0.02f;     // grid cell of the object's points (m)
constexpr double kModelCell = 2.0;       // grid cell of a model's surface, in patch radii

// The radius of the patch a model's surface sample stands for.
double patch_radius(const ModelSurface& surface) {
    return surface.diameter / std::sqrt(static_cast<double>(surface.points.size())) * 1.5;
}

}  // namespace

void validate(const VerificationOptions& o) {
    const auto fail = [](const std::string& what) {
        throw std::invalid_argument("verification: " + what);
    };
    if (o.candidates < 1) fail("candidates must be >= 1");
    if (o.iterations < 1 || o.iterations > 1000) fail("iterations must be in [1, 1000]");
    if (o.surface_points < 100 || o.surface_points > kMaxModelSurfacePoints)
        fail("surface points must be in [100, " + std::to_string(kMaxModelSurfacePoints) + "]");
    if (!(o.accept_score >= -1.0 && o.accept_score <= 2.0)) fail("accept score must be in [-1, 2]");
    if (!(o.prior_tolerance >= 0.0 && o.prior_tolerance <= 2.0))
        fail("prior tolerance must be in [0, 2]");
    if (!(o.shape_weight >= 0.0 && o.shape_weight <= 2.0)) fail("shape weight must be in [0, 2]");
    if (!(o.resize_weight >= 0.0 && o.resize_weight <= 10.0))
        fail("resize weight must be in [0, 10]");
    if (!(o.inlier_distance > 0.0 && o.inlier_distance < 1.0))
        fail("inlier distance must be in (0, 1) m");
    if (!(o.violation_margin > 0.0 && o.violation_margin < 1.0))
        fail("violation margin must be in (0, 1) m");
    if (!(o.min_inliers >= 0.0 && o.min_inliers <= 1.0)) fail("min inliers must be in [0, 1]");
    if (!(o.max_violations >= 0.0 && o.max_violations <= 1.0))
        fail("max violations must be in [0, 1]");
    o.camera.validate();
}

struct PreparedObservation::Impl {
    Impl(const Observation& observation, const CameraIntrinsics& camera)
        : object(stride_sample(observation.points, kObjectSamples), kObjectCell),
          seen(observation, camera) {
        for (const Eigen::Vector3f& p : object.points()) centroid += p.cast<double>();
        centroid /= static_cast<double>(object.points().size());
    }
    NearestPoints object;
    SeenSpace seen;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
};

PreparedObservation::PreparedObservation(const Observation& observation,
                                         const CameraIntrinsics& camera) {
    camera.validate();
    if (observation.points.size() < 3)
        throw std::invalid_argument("verification: needs at least 3 object points, got " +
                                    std::to_string(observation.points.size()));
    if (observation.frame != nullptr &&
        (observation.frame->width != static_cast<std::uint32_t>(camera.width) ||
         observation.frame->height != static_cast<std::uint32_t>(camera.height) ||
         observation.frame->points.size() !=
             static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height)))
        throw std::invalid_argument("verification: the frame is not an organised " +
                                    std::to_string(camera.width) + "x" +
                                    std::to_string(camera.height) + " cloud");
    impl_ = std::make_unique<Impl>(observation, camera);
}

PreparedObservation::~PreparedObservation() = default;
PreparedObservation::PreparedObservation(PreparedObservation&&) noexcept = default;
PreparedObservation& PreparedObservation::operator=(PreparedObservation&&) noexcept = default;

PoseFit fit_model(const ModelSurface& surface, const Eigen::Matrix4d& view_pose,
                  const Observation& observation, const VerificationOptions& options,
                  bool free_scale) {
    validate(options);
    return fit_model(surface, view_pose, PreparedObservation(observation, options.camera), options,
                     free_scale);
}

struct PreparedModel::Impl {
    explicit Impl(ModelSurface s)
        : surface(std::move(s)),
          tree(surface.points, static_cast<float>(kModelCell * patch_radius(surface))) {}
    ModelSurface surface;
    NearestPoints tree;  // the surface's points, model frame
};

PreparedModel::PreparedModel(ModelSurface surface) {
    check_model_surface(surface, "verification");
    impl_ = std::make_unique<Impl>(std::move(surface));
}

PreparedModel::~PreparedModel() = default;
PreparedModel::PreparedModel(PreparedModel&&) noexcept = default;
PreparedModel& PreparedModel::operator=(PreparedModel&&) noexcept = default;
const ModelSurface& PreparedModel::surface() const { return impl_->surface; }

PoseFit fit_model(const ModelSurface& surface, const Eigen::Matrix4d& view_pose,
                  const PreparedObservation& prepared, const VerificationOptions& options,
                  bool free_scale) {
    return fit_model(PreparedModel(surface), view_pose, prepared, options, free_scale);
}

PoseFit fit_model(const PreparedModel& model, const Eigen::Matrix4d& view_pose,
                  const PreparedObservation& prepared, const VerificationOptions& options,
                  bool free_scale, FitStart start, double must_beat) {
    validate(options);
    if (!view_pose.allFinite()) throw std::invalid_argument("verification: pose is not finite");
    const ModelSurface& surface = model.impl_->surface;
    const NearestPoints& object = prepared.impl_->object;
    const Eigen::Vector3d& centroid = prepared.impl_->centroid;

    // Start: the view's rotation (scale removed), turned towards the object (a training view's),
    // centred on it.
    Eigen::Matrix3d rotation = view_pose.topLeftCorner<3, 3>();
    const double view_scale = std::cbrt(std::abs(rotation.determinant()));
    if (!(view_scale > 0.0)) throw std::invalid_argument("verification: singular view pose");
    rotation /= view_scale;
    if (start == FitStart::kTrainingView) rotation = towards(centroid) * rotation;
    Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
    pose.topLeftCorner<3, 3>() = rotation;
    {
        Eigen::Vector3d visible = Eigen::Vector3d::Zero();
        std::size_t count = 0;
        const Eigen::Vector3d ray = centroid.normalized();
        for (std::size_t i = 0; i < surface.points.size(); ++i)
            if ((rotation * surface.normals[i].cast<double>()).dot(ray) < 0.0) {
                visible += rotation * surface.points[i].cast<double>();
                ++count;
            }
        if (count == 0) {
            for (const Eigen::Vector3f& p : surface.points) visible += rotation * p.cast<double>();
            count = surface.points.size();
        }
        pose.topRightCorner<3, 1>() = centroid - visible / static_cast<double>(count);
    }

    // The model's samples that face the camera under `pose`.
    const std::size_t stride = std::max<std::size_t>(1, surface.points.size() / (4 * kIcpSamples));
    const auto visible_samples =
        [&](const Eigen::Matrix4d& m, std::size_t step, std::vector<Eigen::Vector3d>& points,
            std::vector<Eigen::Vector3d>& normals, std::vector<std::size_t>& indices) {
            points.clear();
            normals.clear();
            indices.clear();
            const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
            const Eigen::Vector3d t = m.topRightCorner<3, 1>();
            for (std::size_t i = 0; i < surface.points.size(); i += step) {
                const Eigen::Vector3d p = r * surface.points[i].cast<double>() + t;
                const Eigen::Vector3d n = r * surface.normals[i].cast<double>();
                if (n.dot(p) < 0.0) {  // facing the camera (the length does not change the sign)
                    points.push_back(p);
                    normals.push_back(n.normalized());
                    indices.push_back(i);
                }
            }
        };

    // The object point nearest to a model point, within `radius` (the search grid). ICP pairs
    // points so: projective association (a point with the object points seen at its pixel) cost
    // accuracy on the real views and the pose benchmark (BENCHMARKS.md).
    // Each surface sample's match of the last iteration starts its next search (the same
    // answer, found sooner: BENCHMARKS.md, "Each ICP search starts from the sample's last match").
    std::vector<std::size_t> matches(surface.points.size(), kNoMatch);
    const auto pair = [&](const Eigen::Vector3d& p, std::size_t sample, Eigen::Vector3d& target,
                          double radius) {
        std::size_t index = 0;
        float squared_float = 0.0f;
        if (!object.nearest_within(p.cast<float>(), static_cast<float>(radius * radius),
                                   matches[sample], index, squared_float))
            return false;
        matches[sample] = index;
        target = object.points()[index].cast<double>();
        return true;
    };

    // Two-way: each paired object point's match of the last iteration starts its next search,
    // as the samples' do.
    std::vector<std::size_t> object_matches;
    std::vector<Eigen::Vector3d> points, normals;
    std::vector<std::size_t> indices;
    double scale = 1.0;  // relative to the surface's
    for (int iteration = 0; iteration < options.iterations; ++iteration) {
        const double radius =
            options.iterations > 1
                ? 0.03 + (0.01 - 0.03) * iteration / static_cast<double>(options.iterations - 1)
                : 0.02;
        visible_samples(pose, stride, points, normals, indices);
        // Linearised about the samples' centre, so that rotation and translation separate;
        // point-to-plane with a little point-to-point, so that directions the normals leave
        // free (along a cylinder's axis) stay put.
        Eigen::Vector3d pivot = Eigen::Vector3d::Zero();
        for (const Eigen::Vector3d& p : points) pivot += p;
        if (!points.empty()) pivot /= static_cast<double>(points.size());
        // Unknowns: rotation (3), translation (3), and a scale change where the scale is free.
        Eigen::Matrix<double, 7, 7> ata = Eigen::Matrix<double, 7, 7>::Zero();
        Eigen::Matrix<double, 7, 1> atb = Eigen::Matrix<double, 7, 1>::Zero();
        std::size_t pairs = 0;
        // The point-to-point rows of a pair, [-[arm]x | I | arm], summed in closed form: their
        // normal equations need only these sums (arm: the point about the pivot, d: its offset).
        double arm_squared = 0.0, arm_dot_d = 0.0;
        Eigen::Matrix3d arm_outer = Eigen::Matrix3d::Zero();
        Eigen::Vector3d arm_sum = Eigen::Vector3d::Zero(), arm_cross_d = Eigen::Vector3d::Zero(),
                        d_sum = Eigen::Vector3d::Zero();
        // A pair: a model sample (`arm` about the pivot, unit normal `n`) and its offset `d` to
        // the object point it is paired with. Inlined into both loops: a call per pair costs a
        // few percent of ICP.
        const auto add_pair = [&](const Eigen::Vector3d& arm, const Eigen::Vector3d& n,
                                  const Eigen::Vector3d& d) __attribute__((always_inline)) {
            Eigen::Matrix<double, 7, 1> row;
            row.head<3>() = arm.cross(n);
            row.segment<3>(3) = n;
            row(6) = arm.dot(n);
            ata.noalias() += row * row.transpose();  // inlined: Eigen's rankUpdate is a call
            atb += row * d.dot(n);
            arm_squared += arm.squaredNorm();
            arm_outer.noalias() += arm * arm.transpose();
            arm_sum += arm;
            arm_cross_d += arm.cross(d);
            d_sum += d;
            arm_dot_d += arm.dot(d);
            ++pairs;
        };
        const std::size_t step = std::max<std::size_t>(1, points.size() / kIcpSamples);
        for (std::size_t i = 0; i < points.size(); i += step) {
            Eigen::Vector3d target;
            if (!pair(points[i], indices[i], target, radius)) continue;
            add_pair(points[i] - pivot, normals[i], target - points[i]);
        }
        // Two-way: object points paired with their nearest camera-facing model sample too, so
        // that the model is drawn to cover the object as well as to lie on it (the one-way
        // pairs alone pull a model's samples beyond a cut or hidden edge in, and a free size
        // shrinks towards its bound).
        if (options.two_way) {
            const Eigen::Matrix3d r = pose.topLeftCorner<3, 3>();
            const Eigen::Matrix3d r_t = r.transpose() / (scale * scale);
            const Eigen::Vector3d t = pose.topRightCorner<3, 1>();
            const NearestPoints& tree = model.impl_->tree;
            const double reach = radius / scale;
            const std::size_t n = object.points().size();
            const std::size_t object_step = std::max<std::size_t>(1, n / kIcpSamples);
            if (object_matches.empty()) object_matches.assign(n / object_step + 1, kNoMatch);
            for (std::size_t k = 0; k < n; k += object_step) {
                const Eigen::Vector3d q = object.points()[k].cast<double>();
                const Eigen::Vector3d local = r_t * (q - t);
                float squared = 0.0f;
                std::size_t m = 0;
                std::size_t& hint = object_matches[k / object_step];
                if (!tree.nearest_within(local.cast<float>(), static_cast<float>(reach * reach),
                                         hint, m, squared))
                    continue;
                hint = m;
                const Eigen::Vector3d p = r * surface.points[m].cast<double>() + t;
                Eigen::Vector3d nrm = r * surface.normals[m].cast<double>();
                if (nrm.dot(p) >= 0.0) continue;  // a sample facing away
                add_pair(p - pivot, nrm.normalized(), q - p);
            }
        }
        if (pairs < 7) break;
        {
            Eigen::Matrix3d skew;  // [arm_sum]x
            skew << 0.0, -arm_sum.z(), arm_sum.y(), arm_sum.z(), 0.0, -arm_sum.x(), -arm_sum.y(),
                arm_sum.x(), 0.0;
            Eigen::Matrix<double, 7, 7> point = Eigen::Matrix<double, 7, 7>::Zero();
            point.topLeftCorner<3, 3>() = arm_squared * Eigen::Matrix3d::Identity() - arm_outer;
            point.block<3, 3>(0, 3) = skew;
            point.block<3, 3>(3, 0) = skew.transpose();
            point.block<3, 3>(3, 3) = static_cast<double>(pairs) * Eigen::Matrix3d::Identity();
            point.block<3, 1>(3, 6) = arm_sum;
            point.block<1, 3>(6, 3) = arm_sum.transpose();
            point(6, 6) = arm_squared;
            ata += kPointWeight * point;
            atb.head<3>() += kPointWeight * arm_cross_d;
            atb.segment<3>(3) += kPointWeight * d_sum;
            atb(6) += kPointWeight * arm_dot_d;
        }
        Eigen::Matrix<double, 7, 1> x = Eigen::Matrix<double, 7, 1>::Zero();
        if (free_scale) {
            x = ata.ldlt().solve(atb);
        } else {
            x.head<6>() = ata.topLeftCorner<6, 6>().ldlt().solve(atb.head<6>());
        }
        if (!x.allFinite()) break;
        const double next_scale = std::clamp(scale * (1.0 + x(6)), kMinScale, kMaxScale);
        // p -> (1 + ds) R (p - pivot) + pivot + t
        Eigen::Matrix4d to_pivot = Eigen::Matrix4d::Identity(), back = Eigen::Matrix4d::Identity();
        to_pivot.topRightCorner<3, 1>() = -pivot;
        back.topRightCorner<3, 1>() = pivot;
        Eigen::Matrix4d step_pose = exp_se3(x.head<6>());
        step_pose.topLeftCorner<3, 3>() *= next_scale / scale;
        scale = next_scale;
        pose = back * step_pose * to_pivot * pose;
        if (x.head<3>().norm() < 1e-5 && x.segment<3>(3).norm() < 1e-5 && std::abs(x(6)) < 1e-5)
            break;
    }

    // Score under the final pose. A hypothesis cannot win once the score of the bounds of its
    // parts (at most its inliers and support, at least its violations) falls short of must_beat.
    const auto cannot_win = [&](double inliers, double support, double violations) {
        const FitScore bound{.inliers = inliers, .violations = violations, .support = support};
        return bound.score() < must_beat - kBoundSlack;
    };
    PoseFit out;
    out.model_to_camera = pose;
    out.scale = scale;
    visible_samples(pose, 1, points, normals, indices);
    {
        // The object's points taken into the model's frame, where its grid was built once:
        // the pose is scale times a rotation, so distances shrink by the scale there.
        const Eigen::Matrix3d rotation_t = pose.topLeftCorner<3, 3>().transpose() / scale;
        const Eigen::Vector3d t = pose.topRightCorner<3, 1>();
        const NearestPoints& tree = model.impl_->tree;
        const double reach = (patch_radius(surface) + options.inlier_distance) / scale;
        std::size_t inliers = 0;
        double squared_sum = 0.0;
        const std::size_t n = object.points().size();
        for (std::size_t k = 0; k < n; ++k) {
            // At most: every point left an inlier, all the surface supported, nothing violated.
            if (k % kBoundEvery == 0 &&
                cannot_win(static_cast<double>(inliers + n - k) / static_cast<double>(n), 1.0,
                           0.0)) {
                out.abandoned = true;
                return out;
            }
            const Eigen::Vector3f& q = object.points()[k];
            const Eigen::Vector3d local = rotation_t * (q.cast<double>() - t) / scale;
            float squared = 0.0f;
            std::size_t m = 0;
            if (!tree.nearest_within(local.cast<float>(), static_cast<float>(reach * reach),
                                     kNoMatch, m, squared))
                continue;
            const Eigen::Vector3d d = local - surface.points[m].cast<double>();
            const double along = scale * std::abs(d.dot(surface.normals[m].cast<double>()));
            if (along < options.inlier_distance) {
                ++inliers;
                squared_sum += along * along;
            }
        }
        out.fit.inliers =
            static_cast<double>(inliers) / static_cast<double>(object.points().size());
        out.fit.rms_mm =
            inliers ? 1000.0 * std::sqrt(squared_sum / static_cast<double>(inliers)) : 0.0;
    }
    // Violations, and support: the share of the visible surface (not hidden by something
    // nearer) that has an object point on it.
    const SeenSpace& seen = prepared.impl_->seen;
    std::size_t decided = 0, violations = 0, exposed = 0, supported = 0;
    const double object_spacing = 0.01;
    for (std::size_t i = 0; i < points.size(); ++i) {
        // At most: every sample left exposed and supported, and none a violation.
        if (i % kBoundEvery == 0 && i > 0) {
            const std::size_t left = points.size() - i;
            const double support_bound =
                exposed + left > 0
                    ? static_cast<double>(supported + left) / static_cast<double>(exposed + left)
                    : 0.0;
            const double violation_bound =
                decided + left > 0
                    ? static_cast<double>(violations) / static_cast<double>(decided + left)
                    : 0.0;
            if (cannot_win(out.fit.inliers, support_bound, violation_bound)) {
                out.abandoned = true;
                return out;
            }
        }
        const Eigen::Vector3d& p = points[i];
        const SeenSpace::Look look = seen.look(p, options.violation_margin);
        if (look.violation >= 0) {
            ++decided;
            violations += static_cast<std::size_t>(look.violation);
        }
        if (look.hidden) continue;
        ++exposed;
        // Looked up by pixel among the object's points, the support came out lower at the rim
        // of the object than by the nearest of its samples, and the proving ground lost
        // (BENCHMARKS.md): the nearest sample stays.
        Eigen::Vector3d q;
        if (pair(p, indices[i], q, object_spacing + options.inlier_distance) &&
            std::abs((q - p).dot(normals[i])) < options.inlier_distance)
            ++supported;
    }
    out.fit.violations =
        decided ? static_cast<double>(violations) / static_cast<double>(decided) : 0.0;
    out.fit.support = exposed ? static_cast<double>(supported) / static_cast<double>(exposed) : 0.0;
    out.verified =
        out.fit.inliers >= options.min_inliers && out.fit.violations <= options.max_violations;
    if (cannot_win(out.fit.inliers, out.fit.support, out.fit.violations)) {  // sure only now
        out.abandoned = true;
        out.verified = false;
    }
    return out;
}

}  // namespace esf
