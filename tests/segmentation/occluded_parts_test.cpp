#include "segmentation/occluded_parts.hpp"

#include <gtest/gtest.h>

#include "esf/segmentation/segmentation.hpp"
#include "support/box_scene.hpp"

namespace {

// The camera 1.3 m from a wide box on a table 50 cm below it, a narrow tall box standing in
// front of its middle: the wide box is seen in two parts.
esf::test::CastScene occluded_scene() {
    const float table = 0.5f;
    return esf::test::cast_boxes(
        {
            {{-0.15f, table - 0.10f, 1.45f}, {0.15f, table, 1.55f}},  // behind
            {{-0.03f, table - 0.25f, 1.25f}, {0.03f, table, 1.31f}},  // in front
        },
        table);
}

std::size_t clusters_holding(const esf::SegmentationResult& r, const esf::test::CastScene& scene,
                             int owner) {
    std::size_t n = 0;
    for (const esf::Cluster& c : r.clusters) {
        std::size_t mine = 0;
        for (const std::uint32_t i : c.indices) mine += scene.owner[i] == owner;
        n += mine > 0;
    }
    return n;
}

TEST(OccludedParts, TheTwoSidesOfAnOccludedBoxAreOneObject) {
    const esf::test::CastScene scene = occluded_scene();
    esf::SegmentationOptions options;
    options.threads = 1;
    const esf::SegmentationResult joined = esf::segment_scene(scene.cloud, options);
    ASSERT_TRUE(joined.plane_found) << joined.message;
    EXPECT_EQ(joined.clusters.size(), 2u) << joined.message;
    EXPECT_EQ(clusters_holding(joined, scene, 1), 1u);
    EXPECT_EQ(clusters_holding(joined, scene, 2), 1u);
    options.join_occluded_parts = false;
    const esf::SegmentationResult apart = esf::segment_scene(scene.cloud, options);
    EXPECT_EQ(apart.clusters.size(), 3u) << apart.message;
    EXPECT_EQ(clusters_holding(apart, scene, 1), 2u);
}

TEST(OccludedParts, PartsThatDoNotReachTheSameHeightStayApart) {
    // Two boxes of different heights on either side of the occluder.
    const float table = 0.5f;
    const esf::test::CastScene scene = esf::test::cast_boxes(
        {
            {{-0.15f, table - 0.10f, 1.45f}, {-0.01f, table, 1.55f}},
            {{0.01f, table - 0.16f, 1.45f}, {0.15f, table, 1.55f}},
            {{-0.03f, table - 0.25f, 1.25f}, {0.03f, table, 1.31f}},
        },
        table);
    esf::SegmentationOptions options;
    options.threads = 1;
    const esf::SegmentationResult r = esf::segment_scene(scene.cloud, options);
    EXPECT_EQ(r.clusters.size(), 3u) << r.message;
    EXPECT_EQ(clusters_holding(r, scene, 1), 1u);
    EXPECT_EQ(clusters_holding(r, scene, 2), 1u);
}

}  // namespace
