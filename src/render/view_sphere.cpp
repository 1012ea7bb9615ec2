#include "esf/render/view_sphere.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace esf {
namespace {

void check_level(int level) {
    if (level < 0 || level > kMaxViewSphereLevel)
        throw std::invalid_argument("view sphere level must be in [0, " +
                                    std::to_string(kMaxViewSphereLevel) + "], got " +
                                    std::to_string(level));
}

void subdivide(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
               int level, std::vector<Eigen::Vector3d>& out) {
    if (level == 0) {
        out.push_back((a + b + c).normalized());
        return;
    }
    const Eigen::Vector3d ab = (a + b).normalized();
    const Eigen::Vector3d bc = (b + c).normalized();
    const Eigen::Vector3d ca = (c + a).normalized();
    subdivide(a, ab, ca, level - 1, out);
    subdivide(ab, b, bc, level - 1, out);
    subdivide(ca, bc, c, level - 1, out);
    subdivide(ab, bc, ca, level - 1, out);
}

}  // namespace

std::size_t view_count(int level) {
    check_level(level);
    return std::size_t{20} << (2 * level);
}

std::vector<Eigen::Vector3d> view_sphere(int level) {
    check_level(level);
    const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
    const std::array<Eigen::Vector3d, 12> vertices = {
        Eigen::Vector3d(-1, phi, 0),  Eigen::Vector3d(1, phi, 0),   Eigen::Vector3d(-1, -phi, 0),
        Eigen::Vector3d(1, -phi, 0),  Eigen::Vector3d(0, -1, phi),  Eigen::Vector3d(0, 1, phi),
        Eigen::Vector3d(0, -1, -phi), Eigen::Vector3d(0, 1, -phi),  Eigen::Vector3d(phi, 0, -1),
        Eigen::Vector3d(phi, 0, 1),   Eigen::Vector3d(-phi, 0, -1), Eigen::Vector3d(-phi, 0, 1)};
    // Counter-clockwise seen from outside.
    constexpr std::array<std::array<int, 3>, 20> kFaces = {
        {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
         {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
         {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}}};
    std::vector<Eigen::Vector3d> out;
    out.reserve(view_count(level));
    for (const auto& f : kFaces) {
        subdivide(vertices[static_cast<std::size_t>(f[0])].normalized(),
                  vertices[static_cast<std::size_t>(f[1])].normalized(),
                  vertices[static_cast<std::size_t>(f[2])].normalized(), level, out);
    }
    return out;
}

Eigen::Isometry3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
    if (!eye.allFinite() || !target.allFinite())
        throw std::invalid_argument("look_at: eye and target must be finite");
    const Eigen::Vector3d forward_raw = target - eye;
    if (forward_raw.norm() == 0.0)
        throw std::invalid_argument("look_at: eye and target are the same point");
    const Eigen::Vector3d z = forward_raw.normalized();
    const Eigen::Vector3d up =
        std::abs(z.z()) > 0.99 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d y = -(up - up.dot(z) * z).normalized();  // image down
    const Eigen::Vector3d x = y.cross(z);
    Eigen::Matrix3d rotation;  // rows: camera axes in world coordinates
    rotation.row(0) = x;
    rotation.row(1) = y;
    rotation.row(2) = z;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = rotation;
    pose.translation() = -rotation * eye;
    return pose;
}

}  // namespace esf
