#include "esf/evaluation/segmentation_evaluation.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <numeric>
#include <stdexcept>

namespace {

esf::Cluster cluster_of(std::uint32_t first, std::uint32_t last) {
    esf::Cluster c;
    for (std::uint32_t i = first; i < last; ++i) c.indices.push_back(i);
    return c;
}

TEST(ScoreSegmentation, FoundSplitMergedMissed) {
    // Labels (mOSD scheme): 0-9 table, then objects 2 (20), 3 (30), 4 (40), 5 (50) of 100 each.
    std::vector<std::uint32_t> labels;
    for (int k = 0; k < 100; ++k) labels.push_back(1);
    for (std::uint32_t id : {2u, 3u, 4u, 5u})
        for (int k = 0; k < 100; ++k) labels.push_back(10 * id + 1);
    esf::Points points(labels.size(), Eigen::Vector3f::Zero());
    points[100].x() = std::numeric_limits<float>::quiet_NaN();  // not counted for object 2

    std::vector<esf::Cluster> clusters = {
        cluster_of(101, 200),  // all finite points of object 2: found
        cluster_of(200, 250),  // half of object 3 ...
        cluster_of(250, 300),  // ... and the other half: split
        cluster_of(300, 400),  // object 4 and object 5 together: both merged
        cluster_of(0, 60),     // table only
    };
    for (std::uint32_t i = 400; i < 500; ++i) clusters[3].indices.push_back(i);
    const esf::SegmentationScore s = esf::score_segmentation(points, labels, clusters);
    ASSERT_EQ(s.objects.size(), 4u);
    EXPECT_EQ(s.objects[0].object_id, 2u);
    EXPECT_EQ(s.objects[0].points, 99u);
    EXPECT_EQ(s.objects[0].outcome, esf::SegmentOutcome::kFound);
    EXPECT_DOUBLE_EQ(s.objects[0].coverage, 1.0);
    EXPECT_EQ(s.objects[1].outcome, esf::SegmentOutcome::kSplit);
    EXPECT_EQ(s.objects[1].parts, 2u);
    EXPECT_EQ(s.objects[2].outcome, esf::SegmentOutcome::kMerged);
    EXPECT_DOUBLE_EQ(s.objects[2].purity, 0.5);
    EXPECT_EQ(s.objects[3].outcome, esf::SegmentOutcome::kMerged);
    EXPECT_EQ(s.count(esf::SegmentOutcome::kFound), 1u);
    EXPECT_EQ(s.clusters, 5u);
    EXPECT_EQ(s.background_clusters, 1u);
    EXPECT_EQ(s.shared_clusters, 1u);

    // A small piece only: missed; no cluster at all: missed.
    const esf::SegmentationScore small =
        esf::score_segmentation(points, labels, {cluster_of(101, 110)});
    EXPECT_EQ(small.objects[0].outcome, esf::SegmentOutcome::kMissed);
    EXPECT_EQ(small.objects[1].outcome, esf::SegmentOutcome::kMissed);
    EXPECT_EQ(small.objects[1].cluster, -1);
}

TEST(ScoreSegmentation, RefusesMismatchedInput) {
    const esf::Points points(3, Eigen::Vector3f::Zero());
    EXPECT_THROW(esf::score_segmentation(points, std::vector<std::uint32_t>{1, 2}, {}),
                 std::invalid_argument);
    esf::Cluster c;
    c.indices = {7};
    EXPECT_THROW(esf::score_segmentation(points, std::vector<std::uint32_t>{1, 2, 3}, {c}),
                 std::invalid_argument);
    esf::SegmentationCriteria bad;
    bad.min_purity = 0.0;
    EXPECT_THROW(esf::score_segmentation(points, std::vector<std::uint32_t>{1, 2, 3}, {}, {}, bad),
                 std::invalid_argument);
}

}  // namespace
