// Occluded copies of a view (esf/render/occluded_view.hpp).

#include "esf/render/occluded_view.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/splitmix64.hpp"

namespace esf {

namespace {

constexpr std::uint64_t kOcclusionKey = 0x6f63636c75646564ull;  // "occluded"

}  // namespace

Points occlude_view(std::span<const Eigen::Vector3f> points, double angle, double fraction) {
    if (!(fraction >= 0.0 && fraction <= 1.0)) {
        std::ostringstream msg;
        msg << "occlude_view: fraction " << fraction << " is not in [0, 1]";
        throw std::invalid_argument(msg.str());
    }
    if (!std::isfinite(angle)) throw std::invalid_argument("occlude_view: angle is not finite");
    const double c = std::cos(angle), s = std::sin(angle);
    std::vector<std::pair<double, std::size_t>> order(points.size());  // (image position, index)
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector3f& p = points[i];
        if (!p.allFinite() || !(p.z() > 0.0f))
            throw std::invalid_argument("occlude_view: point " + std::to_string(i) +
                                        " is not finite or not in front of the camera");
        order[i] = {(p.x() * c + p.y() * s) / p.z(), i};
    }
    const auto hidden =
        static_cast<std::size_t>(std::floor(fraction * static_cast<double>(points.size())));
    // The hidden points are the `hidden` first in (position, index) order: a strict order, so
    // the split does not depend on the algorithm.
    std::vector<bool> drop(points.size(), false);
    if (hidden > 0) {
        std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(hidden - 1),
                         order.end());
        for (std::size_t j = 0; j < hidden; ++j) drop[order[j].second] = true;
    }
    Points out;
    out.reserve(points.size() - hidden);
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!drop[i]) out.push_back(points[i]);
    return out;
}

OcclusionEdge occlusion_edge(std::uint64_t view_seed, std::uint32_t copy) {
    std::uint64_t state = detail::mix64(view_seed ^ kOcclusionKey) + copy * detail::kGoldenGamma;
    OcclusionEdge edge;
    edge.angle = 2.0 * std::numbers::pi * detail::splitmix64_uniform(state);
    edge.fraction = kMinOccludedFraction + (kMaxOccludedFraction - kMinOccludedFraction) *
                                               detail::splitmix64_uniform(state);
    return edge;
}

}  // namespace esf
