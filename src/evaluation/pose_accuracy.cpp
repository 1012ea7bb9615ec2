// ADD-S and the posed diameter (esf/evaluation/pose_accuracy.hpp).

#include "esf/evaluation/pose_accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

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

}  // namespace esf
