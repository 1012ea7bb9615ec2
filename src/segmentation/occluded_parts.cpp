#include "segmentation/occluded_parts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/disjoint_sets.hpp"
#include "core/pixel_rows.hpp"

namespace esf::detail {

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

struct Group {
    std::size_t points = 0;
    double u = 0.0, v = 0.0;  // image centroid
    float top = -std::numeric_limits<float>::infinity();
};

}  // namespace

void join_occluded_parts(std::span<const Eigen::Vector3f> points, std::uint32_t width,
                         std::uint32_t height, std::span<const std::uint32_t> candidates,
                         std::vector<std::uint32_t>& component, const Eigen::Vector3f& viewpoint,
                         const Eigen::Vector3f& up, float offset,
                         const OccludedPartsOptions& options) {
    if (component.empty()) return;
    const std::uint32_t count = *std::max_element(component.begin(), component.end()) + 1;
    std::vector<Group> groups(count);
    std::vector<std::uint32_t> group_at(static_cast<std::size_t>(width) * height, kNone);
    PixelRows rows(width);
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        Group& g = groups[component[k]];
        ++g.points;
        rows.seek(candidates[k]);
        g.u += rows.col();
        g.v += rows.row();
        g.top = std::max(g.top, up.dot(points[candidates[k]]) + offset);
        group_at[candidates[k]] = component[k];
    }
    std::vector<std::uint32_t> large;
    for (std::uint32_t g = 0; g < count; ++g) {
        groups[g].u /= static_cast<double>(groups[g].points);
        groups[g].v /= static_cast<double>(groups[g].points);
        if (groups[g].points >= options.min_points) large.push_back(g);
    }
    auto range = [&](std::size_t pixel) { return (points[pixel] - viewpoint).norm(); };

    std::vector<std::size_t> line;
    auto hidden_between = [&](std::uint32_t a, std::uint32_t b) {
        const Group &ga = groups[a], &gb = groups[b];
        const double du = gb.u - ga.u, dv = gb.v - ga.v;
        const int steps = static_cast<int>(std::ceil(std::max(std::abs(du), std::abs(dv))));
        line.clear();
        for (int s = 0; s <= steps; ++s) {
            const long u = std::lround(ga.u + du * s / std::max(steps, 1));
            const long v = std::lround(ga.v + dv * s / std::max(steps, 1));
            if (u < 0 || v < 0 || u >= width || v >= height) return false;
            line.push_back(static_cast<std::size_t>(v) * width + static_cast<std::size_t>(u));
        }
        // The last pixel of a before the first pixel of b.
        std::ptrdiff_t first_b = -1;
        for (std::size_t i = 0; i < line.size(); ++i)
            if (group_at[line[i]] == b) {
                first_b = static_cast<std::ptrdiff_t>(i);
                break;
            }
        if (first_b < 0) return false;
        std::ptrdiff_t last_a = -1;
        for (std::ptrdiff_t i = 0; i < first_b; ++i)
            if (group_at[line[static_cast<std::size_t>(i)]] == a) last_a = i;
        if (last_a < 0 || first_b - last_a < 2) return false;
        const float end_a = range(line[static_cast<std::size_t>(last_a)]);
        const float end_b = range(line[static_cast<std::size_t>(first_b)]);
        const float across = (points[line[static_cast<std::size_t>(last_a)]] -
                              points[line[static_cast<std::size_t>(first_b)]])
                                 .norm();
        if (std::abs(end_a - end_b) > options.max_end_gap + options.max_end_slope * across)
            return false;
        const float limit = std::min(end_a, end_b) - options.min_occluder_gap;
        std::size_t invalid = 0, between = 0;
        for (std::ptrdiff_t i = last_a + 1; i < first_b; ++i) {
            const std::size_t pixel = line[static_cast<std::size_t>(i)];
            ++between;
            if (!points[pixel].allFinite()) {
                ++invalid;
                continue;
            }
            const std::uint32_t g = group_at[pixel];
            if (g == kNone || g == a || g == b || !(range(pixel) <= limit)) return false;
        }
        return static_cast<double>(invalid) <=
                   static_cast<double>(options.max_invalid_share) * static_cast<double>(between) &&
               invalid < between;
    };
    DisjointSets sets(count);
    for (std::size_t i = 0; i < large.size(); ++i)
        for (std::size_t j = i + 1; j < large.size(); ++j) {
            const std::uint32_t a = large[i], b = large[j];
            if (std::abs(groups[a].top - groups[b].top) > options.max_top_difference) continue;
            if (hidden_between(a, b)) sets.unite(a, b);
        }
    sets.number_sets(component);
}

}  // namespace esf::detail
