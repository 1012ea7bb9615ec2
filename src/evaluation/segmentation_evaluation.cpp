#include "esf/evaluation/segmentation_evaluation.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>

namespace esf {

std::size_t SegmentationScore::count(SegmentOutcome outcome) const {
    return static_cast<std::size_t>(
        std::count_if(objects.begin(), objects.end(),
                      [&](const ObjectSegmentation& o) { return o.outcome == outcome; }));
}

SegmentationScore score_segmentation(std::span<const Eigen::Vector3f> points,
                                     std::span<const std::uint32_t> labels,
                                     const std::vector<Cluster>& clusters,
                                     const LabelScheme& scheme,
                                     const SegmentationCriteria& criteria) {
    if (labels.size() != points.size())
        throw std::invalid_argument("score_segmentation: " + std::to_string(labels.size()) +
                                    " labels for " + std::to_string(points.size()) + " points");
    if (scheme.divisor < 1) throw std::invalid_argument("score_segmentation: label divisor 0");
    auto in_unit = [](double v) { return v > 0.0 && v <= 1.0; };
    if (!in_unit(criteria.min_coverage) || !in_unit(criteria.min_purity) ||
        !in_unit(criteria.min_share))
        throw std::invalid_argument(
            "score_segmentation: coverage, purity and share must be in (0, 1]");
    auto object_of = [&](std::size_t i) -> std::uint32_t {
        const std::uint32_t id = labels[i] / scheme.divisor;
        return id >= scheme.first_object ? id : 0;
    };

    // Finite points per object.
    std::map<std::uint32_t, std::size_t> object_points;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (points[i].allFinite() && object_of(i) != 0) ++object_points[object_of(i)];

    // Points of each object in each cluster.
    std::map<std::uint32_t, std::vector<std::size_t>> per_cluster;  // object -> count per cluster
    for (const auto& [id, count] : object_points) per_cluster[id].assign(clusters.size(), 0);
    SegmentationScore score;
    score.clusters = clusters.size();
    for (std::size_t c = 0; c < clusters.size(); ++c) {
        std::size_t background = 0;
        for (const std::uint32_t i : clusters[c].indices) {
            if (i >= points.size())
                throw std::invalid_argument("score_segmentation: cluster " + std::to_string(c) +
                                            " holds point " + std::to_string(i) +
                                            " of a cloud of " + std::to_string(points.size()));
            const std::uint32_t id = object_of(i);
            if (id == 0)
                ++background;
            else
                ++per_cluster[id][c];
        }
        if (2 * background > clusters[c].indices.size()) ++score.background_clusters;
    }
    std::vector<std::size_t> objects_in_cluster(clusters.size(), 0);
    for (const auto& [id, count] : object_points) {
        const std::vector<std::size_t>& in = per_cluster[id];
        ObjectSegmentation o;
        o.object_id = id;
        o.points = count;
        for (std::size_t c = 0; c < clusters.size(); ++c) {
            if (in[c] > o.in_cluster) {
                o.in_cluster = in[c];
                o.cluster = static_cast<std::ptrdiff_t>(c);
            }
            if (static_cast<double>(in[c]) >= criteria.min_share * static_cast<double>(count)) {
                ++o.parts;
                ++objects_in_cluster[c];
            }
        }
        if (o.cluster >= 0) {
            o.coverage = static_cast<double>(o.in_cluster) / static_cast<double>(count);
            o.purity =
                static_cast<double>(o.in_cluster) /
                static_cast<double>(clusters[static_cast<std::size_t>(o.cluster)].indices.size());
            if (o.coverage >= criteria.min_coverage && o.purity >= criteria.min_purity)
                o.outcome = SegmentOutcome::kFound;
            else if (o.purity < criteria.min_purity)
                o.outcome = SegmentOutcome::kMerged;
            else if (o.parts >= 2)
                o.outcome = SegmentOutcome::kSplit;
        }
        score.objects.push_back(o);
    }
    for (const std::size_t n : objects_in_cluster)
        if (n >= 2) ++score.shared_clusters;
    return score;
}

}  // namespace esf
