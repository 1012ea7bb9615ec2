#include "esf/core/point_cloud.hpp"

#include "core/finite_points.hpp"
#include "esf/core/error.hpp"

namespace esf {

FinitePoints drop_non_finite(std::span<const Eigen::Vector3f> points) {
    FinitePoints out;
    out.dropped = drop_non_finite(points, out.points);
    return out;
}

std::size_t drop_non_finite(std::span<const Eigen::Vector3f> points, Points& finite) {
    return detail::keep_finite_points(points, detail::best_simd_level(), finite);
}

std::string file_message(const std::string& path, std::size_t line, const std::string& reason) {
    return line == 0 ? path + ": " + reason : path + ":" + std::to_string(line) + ": " + reason;
}

}  // namespace esf
