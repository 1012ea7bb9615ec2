#include "esf/segmentation/convexity_grouping.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "core/disjoint_sets.hpp"

namespace esf {

namespace {

constexpr float kPi = 3.14159265358979f;

float radians(float degrees) { return degrees * kPi / 180.0f; }

}  // namespace

void validate(const ConvexityOptions& o) {
    auto fail = [](const std::string& what) {
        throw std::invalid_argument("convexity options: " + what);
    };
    if (!(o.concavity_tolerance_deg >= 0.0f && o.concavity_tolerance_deg < 90.0f))
        fail("concavity_tolerance_deg must be in [0, 90), got " +
             std::to_string(o.concavity_tolerance_deg));
    if (o.smoothing_passes < 0 || o.smoothing_passes > 16)
        fail("smoothing_passes must be in [0, 16], got " + std::to_string(o.smoothing_passes));
    if (!(o.lip_angle_deg >= 0.0f && o.lip_angle_deg <= 90.0f))
        fail("lip_angle_deg must be in [0, 90], got " + std::to_string(o.lip_angle_deg));
    if (!(o.sanity_angle_deg >= 0.0f && o.sanity_angle_deg <= 90.0f))
        fail("sanity_angle_deg must be in [0, 90], got " + std::to_string(o.sanity_angle_deg));
}

bool convex_connection(const SurfacePatch& a, const SurfacePatch& b,
                       const ConvexityOptions& options) {
    if (!a.has_normal() || !b.has_normal()) return false;
    const float cos_between = std::clamp(a.normal.dot(b.normal), -1.0f, 1.0f);
    if (cos_between >= std::cos(radians(options.concavity_tolerance_deg))) return true;
    const Eigen::Vector3f offset = a.centroid - b.centroid;
    const float distance = offset.norm();
    if (!(distance > 0.0f)) return false;
    const Eigen::Vector3f d = offset / distance;
    if ((a.normal - b.normal).dot(d) <= 0.0f) return false;  // concave
    // Nearly opposite normals, convex: the two sides of a thin wall meeting at its rim (a cup's
    // or a bowl's lip); the crease direction is too ill-conditioned to test.
    if (cos_between <= std::cos(radians(180.0f - options.lip_angle_deg))) return true;
    const Eigen::Vector3f crease = a.normal.cross(b.normal);
    const float crease_norm = crease.norm();
    if (!(crease_norm > 0.0f)) return true;
    const float cos_to_crease = std::abs(d.dot(crease)) / crease_norm;
    return cos_to_crease <= std::cos(radians(options.sanity_angle_deg));
}

std::vector<std::uint32_t> convex_segments(const PatchGraph& graph,
                                           const ConvexityOptions& options) {
    validate(options);
    const std::size_t n = graph.patches.size();
    // Normals smoothed over the smooth neighbourhood (bilateral: neighbours across a crease do
    // not count), so that sensor noise does not fake concave creases on curved walls.
    std::vector<SurfacePatch> patches = graph.patches;
    if (options.smoothing_passes > 0) {
        const float cos_smooth = std::cos(radians(options.concavity_tolerance_deg));
        for (int pass = 0; pass < options.smoothing_passes; ++pass) {
            std::vector<Eigen::Vector3f> sum(n, Eigen::Vector3f::Zero());
            for (std::size_t p = 0; p < n; ++p)
                sum[p] = static_cast<float>(patches[p].points) * patches[p].normal;
            for (const PatchEdge& e : graph.edges) {
                const SurfacePatch &a = patches[e.a], &b = patches[e.b];
                if (!a.has_normal() || !b.has_normal() || a.normal.dot(b.normal) < cos_smooth)
                    continue;
                sum[e.a] += static_cast<float>(b.points) * b.normal;
                sum[e.b] += static_cast<float>(a.points) * a.normal;
            }
            for (std::size_t p = 0; p < n; ++p)
                if (patches[p].has_normal() && sum[p].squaredNorm() > 0.0f)
                    patches[p].normal = sum[p].normalized();
        }
    }
    DisjointSets sets(n);
    for (const PatchEdge& e : graph.edges)
        if (convex_connection(patches[e.a], patches[e.b], options)) sets.unite(e.a, e.b);

    // Points per segment (indexed by root).
    std::vector<std::uint64_t> size(n, 0);
    for (std::uint32_t p = 0; p < n; ++p) size[sets.find(p)] += graph.patches[p].points;

    // Small segments join the neighbour they touch most, smallest first.
    std::vector<std::uint32_t> small;
    for (std::uint32_t p = 0; p < n; ++p)
        if (sets.find(p) == p && size[p] < options.min_segment_points) small.push_back(p);
    if (!small.empty()) {
        std::stable_sort(small.begin(), small.end(),
                         [&](std::uint32_t x, std::uint32_t y) { return size[x] < size[y]; });
        // Edges of each patch, in compressed rows.
        std::vector<std::uint32_t> start(n + 1, 0);
        for (const PatchEdge& e : graph.edges) {
            ++start[e.a + 1];
            ++start[e.b + 1];
        }
        std::partial_sum(start.begin(), start.end(), start.begin());
        std::vector<std::uint32_t> other(start.back()), contacts(start.back());
        {
            std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
            for (const PatchEdge& e : graph.edges) {
                other[fill[e.a]] = e.b;
                contacts[fill[e.a]++] = e.contacts;
                other[fill[e.b]] = e.a;
                contacts[fill[e.b]++] = e.contacts;
            }
        }
        // Patches of each segment at the time of the first pass.
        std::vector<std::uint32_t> order(n);
        std::iota(order.begin(), order.end(), std::uint32_t{0});
        std::vector<std::uint32_t> root_of(n);
        for (std::uint32_t p = 0; p < n; ++p) root_of[p] = sets.find(p);
        std::stable_sort(order.begin(), order.end(),
                         [&](std::uint32_t x, std::uint32_t y) { return root_of[x] < root_of[y]; });
        std::vector<std::uint32_t> first(n + 1, 0);
        for (std::uint32_t p = 0; p < n; ++p) ++first[root_of[p] + 1];
        std::partial_sum(first.begin(), first.end(), first.begin());

        std::vector<std::uint64_t> touch(n, 0);
        std::vector<std::uint32_t> touched;
        for (const std::uint32_t segment : small) {
            const std::uint32_t root = sets.find(segment);
            if (size[root] >= options.min_segment_points) continue;
            touched.clear();
            for (std::uint32_t k = first[segment]; k < first[segment + 1]; ++k) {
                const std::uint32_t p = order[k];
                for (std::uint32_t j = start[p]; j < start[p + 1]; ++j) {
                    const std::uint32_t r = sets.find(other[j]);
                    if (r == root) continue;
                    if (touch[r] == 0) touched.push_back(r);
                    touch[r] += contacts[j];
                }
            }
            std::uint32_t best = std::numeric_limits<std::uint32_t>::max();
            for (const std::uint32_t r : touched) {
                if (best == std::numeric_limits<std::uint32_t>::max() || touch[r] > touch[best] ||
                    (touch[r] == touch[best] && r < best))
                    best = r;
            }
            for (const std::uint32_t r : touched) touch[r] = 0;
            if (best == std::numeric_limits<std::uint32_t>::max()) continue;
            const std::uint64_t merged = size[root] + size[best];
            sets.unite(root, best);
            size[sets.find(root)] = merged;
        }
    }

    std::vector<std::uint32_t> segment(n);
    std::iota(segment.begin(), segment.end(), std::uint32_t{0});
    sets.number_sets(segment);
    return segment;
}

}  // namespace esf
