#pragma once
// Scores a scene segmentation against per-point object labels. An object counts as found when
// one cluster holds at least `min_coverage` of its points and at least `min_purity` of that
// cluster's points are the object's (80 % and 80 % by default, the criterion of the project's
// scene figures in BENCHMARKS.md).
//
// Labels: the object id of a point is `label / divisor`; ids below `first_object` are the
// background (the table, unlabelled points). The defaults follow the Object Segmentation
// Database (Richtsfeld et al., IROS 2012) as distributed with PCL: label 0 invalid, 1-9 the
// table, 10 k + j a point of object k >= 2.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "esf/core/enum_names.hpp"
#include "esf/segmentation/segmentation.hpp"

namespace esf {

struct LabelScheme {
    std::uint32_t divisor = 10;      ///< >= 1
    std::uint32_t first_object = 2;  ///< object ids start here
};

struct SegmentationCriteria {
    double min_coverage = 0.8;  ///< (0, 1]
    double min_purity = 0.8;    ///< (0, 1]
    /// A cluster (or object) holds a part of an object when at least this share of the object's
    /// points: used to count splits and clusters that hold several objects.
    double min_share = 0.1;
};

enum class SegmentOutcome {
    kFound,   ///< one cluster, coverage and purity met
    kMerged,  ///< its main cluster is mostly something else (glued to neighbours or the table)
    kSplit,   ///< its main cluster is pure but holds too little; other clusters hold parts
    kMissed,  ///< in no cluster, or only a small part of it is
};

/// "found", "merged", "split", "missed".
template <>
struct EnumNames<SegmentOutcome> {
    static constexpr const char* what = "segment outcome";
    static constexpr std::array<EnumName<SegmentOutcome>, 4> table{
        {{SegmentOutcome::kFound, "found"},
         {SegmentOutcome::kMerged, "merged"},
         {SegmentOutcome::kSplit, "split"},
         {SegmentOutcome::kMissed, "missed"}}};
};

struct ObjectSegmentation {
    std::uint32_t object_id = 0;
    std::size_t points = 0;       ///< finite labelled points
    std::ptrdiff_t cluster = -1;  ///< index of the cluster holding most of them; -1: none
    std::size_t in_cluster = 0;   ///< of its points in that cluster
    double coverage = 0.0;        ///< in_cluster / points
    double purity = 0.0;          ///< in_cluster / that cluster's size
    std::size_t parts = 0;        ///< clusters holding at least min_share of its points
    SegmentOutcome outcome = SegmentOutcome::kMissed;
};

struct SegmentationScore {
    std::vector<ObjectSegmentation> objects;  ///< by object id
    std::size_t clusters = 0;
    std::size_t background_clusters = 0;  ///< clusters whose points are mostly background
    std::size_t shared_clusters = 0;      ///< clusters holding parts of two or more objects
    std::size_t count(SegmentOutcome outcome) const;
};

/// Throws std::invalid_argument when the labels do not match the points, or for bad criteria.
SegmentationScore score_segmentation(std::span<const Eigen::Vector3f> points,
                                     std::span<const std::uint32_t> labels,
                                     const std::vector<Cluster>& clusters,
                                     const LabelScheme& scheme = {},
                                     const SegmentationCriteria& criteria = {});

}  // namespace esf
