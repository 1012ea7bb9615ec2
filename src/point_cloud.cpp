#include "esf/point_cloud.hpp"

#include "esf/error.hpp"

namespace esf {

FinitePoints drop_non_finite(std::span<const Eigen::Vector3f> points) {
    FinitePoints out;
    out.points.reserve(points.size());
    for (const auto& p : points) {
        if (p.allFinite()) {
            out.points.push_back(p);
        } else {
            ++out.dropped;
        }
    }
    return out;
}

std::string file_message(const std::string& path, std::size_t line, const std::string& reason) {
    return line == 0 ? path + ": " + reason : path + ":" + std::to_string(line) + ": " + reason;
}

}  // namespace esf
