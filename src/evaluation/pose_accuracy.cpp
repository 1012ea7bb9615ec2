// ADD-S and the posed diameter (esf/evaluation/pose_accuracy.hpp).

#include "esf/evaluation/pose_accuracy.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "esf/mesh/model_surface.hpp"
#include "recognition/nearest_points.hpp"

namespace esf {

namespace {

std::vector<Eigen::Vector3d> posed(std::span<const Eigen::Vector3f> points,
                                   const Eigen::Matrix4d& pose) {
    if (!pose.allFinite()) throw std::invalid_argument("pose accuracy: pose is not finite");
    std::vector<Eigen::Vector3d> out;
    out.reserve(points.size());
    for (const Eigen::Vector3f& p : points)
        out.push_back(pose.topLeftCorner<3, 3>() * p.cast<double>() + pose.topRightCorner<3, 1>());
    return out;
}

// The rotation of a pose: its 3x3 block over the cube root of its determinant.
Eigen::Matrix3d rotation_of(const Eigen::Matrix4d& pose) {
    if (!pose.allFinite()) throw std::invalid_argument("pose accuracy: pose is not finite");
    const Eigen::Matrix3d linear = pose.topLeftCorner<3, 3>();
    const double det = linear.determinant();
    if (!(det > 0.0))
        throw std::invalid_argument(
            "pose accuracy: the pose's 3x3 block is not a rotation times a positive scale "
            "(determinant " +
            std::to_string(det) + ")");
    return linear / std::cbrt(det);
}

// The q quantile of `values` (the value at rank q (n - 1), rounded down); reorders them.
double quantile(std::vector<double>& values, double q) {
    const auto at = static_cast<std::ptrdiff_t>(q * static_cast<double>(values.size() - 1));
    std::nth_element(values.begin(), values.begin() + at, values.end());
    return values[static_cast<std::size_t>(at)];
}

}  // namespace

double add_s(std::span<const Eigen::Vector3f> model_points, const Eigen::Matrix4d& truth,
             const Eigen::Matrix4d& estimate) {
    if (model_points.empty()) throw std::invalid_argument("pose accuracy: no model points");
    const std::vector<Eigen::Vector3d> a = posed(model_points, truth);
    const std::vector<Eigen::Vector3d> b = posed(model_points, estimate);
    double sum = 0.0;
    for (const Eigen::Vector3d& p : a) {
        double best = std::numeric_limits<double>::infinity();
        for (const Eigen::Vector3d& q : b) best = std::min(best, (p - q).squaredNorm());
        sum += std::sqrt(best);
    }
    return sum / static_cast<double>(a.size());
}

double posed_diameter(std::span<const Eigen::Vector3f> model_points, const Eigen::Matrix4d& truth) {
    const std::vector<Eigen::Vector3d> a = posed(model_points, truth);
    double best = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i)
        for (std::size_t j = i + 1; j < a.size(); ++j)
            best = std::max(best, (a[i] - a[j]).squaredNorm());
    return std::sqrt(best);
}

double rotation_error_degrees(const Eigen::Matrix4d& truth, const Eigen::Matrix4d& estimate) {
    const Eigen::Matrix3d turn = rotation_of(estimate) * rotation_of(truth).transpose();
    const double cosine = std::clamp((turn.trace() - 1.0) / 2.0, -1.0, 1.0);
    return std::acos(cosine) * 180.0 / std::numbers::pi;
}

bool has_symmetry(const Mesh& mesh) {
    const ModelSurface a = sample_model_surface(mesh, 1.0, kSymmetrySamples, 0);
    const ModelSurface b = sample_model_surface(mesh, 1.0, kSymmetrySamples, 1);
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3f& p : a.points) centre += p.cast<double>();
    centre /= static_cast<double>(a.points.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3f& p : a.points) {
        const Eigen::Vector3d d = p.cast<double>() - centre;
        covariance += d * d.transpose();
    }
    const detail::NearestPoints nearest(a.points, static_cast<float>(a.diameter / 64.0));
    std::vector<double> distances(b.points.size());
    // The quantile of the distances from b's samples, turned about the centre, to a's; a
    // distance beyond `reach` counts as infinite (only whether the quantile is within it matters).
    const auto spread = [&](const Eigen::Matrix3d& turn, float reach) {
        for (std::size_t i = 0; i < b.points.size(); ++i) {
            const Eigen::Vector3d q = turn * (b.points[i].cast<double>() - centre) + centre;
            std::size_t index = 0;
            float squared = 0.0f;
            distances[i] = nearest.nearest_within(q.cast<float>(), reach * reach, a.points.size(),
                                                  index, squared)
                               ? std::sqrt(static_cast<double>(squared))
                               : std::numeric_limits<double>::infinity();
        }
        return quantile(distances, kSymmetryQuantile);
    };
    const double bound =
        kSymmetrySlack * spread(Eigen::Matrix3d::Identity(), static_cast<float>(a.diameter));
    std::vector<Eigen::Vector3d> axes;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> principal(covariance);
    for (int k = 0; k < 3; ++k) axes.push_back(principal.eigenvectors().col(k).normalized());
    for (int k = 0; k < 3; ++k) axes.push_back(Eigen::Vector3d::Unit(k));
    for (const Eigen::Vector3d& axis : axes) {
        if (!axis.allFinite()) continue;
        for (const int order : kSymmetryOrders)
            if (spread(Eigen::AngleAxisd(2.0 * std::numbers::pi / order, axis).toRotationMatrix(),
                       static_cast<float>(bound)) <= bound)
                return true;
    }
    return false;
}

}  // namespace esf
