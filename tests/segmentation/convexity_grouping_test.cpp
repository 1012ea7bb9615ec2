#include "esf/segmentation/convexity_grouping.hpp"

#include <gtest/gtest.h>

#include <set>

#include "esf/segmentation/segmentation.hpp"
#include "support/box_scene.hpp"

namespace {

using Eigen::Vector3f;

esf::SurfacePatch patch(const Vector3f& centroid, const Vector3f& normal) {
    esf::SurfacePatch p;
    p.centroid = centroid;
    p.normal = normal.normalized();
    p.points = 50;
    return p;
}

TEST(ConvexConnection, HandComputedCorners) {
    // A box edge seen from the front and above: top face and front face, convex.
    const esf::SurfacePatch top = patch({0, 1, -0.5f}, {0, 1, 0});
    const esf::SurfacePatch front = patch({0, 0.5f, 0}, {0, 0, 1});
    EXPECT_TRUE(esf::convex_connection(top, front));
    EXPECT_TRUE(esf::convex_connection(front, top));
    // The crease where a wall meets the floor in front of it: concave.
    const esf::SurfacePatch floor = patch({0, 0, 0.5f}, {0, 1, 0});
    const esf::SurfacePatch wall = patch({0, 0.5f, 0}, {0, 0, 1});
    EXPECT_FALSE(esf::convex_connection(floor, wall));
    // Slightly concave, within the tolerance (10 degrees of the default 25): smooth.
    const float s = std::sin(0.0873f), c = std::cos(0.0873f);
    const esf::SurfacePatch left = patch({-0.01f, 0, 0}, {s, 0, -c});
    const esf::SurfacePatch right = patch({0.01f, 0, 0}, {-s, 0, -c});
    EXPECT_TRUE(esf::convex_connection(left, right));
    esf::ConvexityOptions strict;
    strict.concavity_tolerance_deg = 5.0f;
    EXPECT_FALSE(esf::convex_connection(left, right, strict));
    // No normal: no connection.
    esf::SurfacePatch none = top;
    none.normal = Vector3f::Zero();
    EXPECT_FALSE(esf::convex_connection(none, front));
    // Singular: the patches lie along the crease direction (sanity criterion).
    const esf::SurfacePatch a = patch({0, 0, 0}, {1, 0, 1});
    const esf::SurfacePatch b = patch({-0.002f, 0.02f, 0}, {-1, 0, 1});
    EXPECT_FALSE(esf::convex_connection(a, b));
    esf::ConvexityOptions no_sanity;
    no_sanity.sanity_angle_deg = 0.0f;
    EXPECT_TRUE(esf::convex_connection(a, b, no_sanity));
    esf::ConvexityOptions bad;
    bad.concavity_tolerance_deg = 90.0f;
    EXPECT_THROW(esf::convex_segments({}, bad), std::invalid_argument);
    bad = {};
    bad.lip_angle_deg = -1.0f;
    EXPECT_THROW(esf::convex_segments({}, bad), std::invalid_argument);
}

TEST(ConvexSegments, SmallSegmentsJoinTheNeighbourTheyTouchMost) {
    esf::PatchGraph graph;
    graph.patches = {patch({0, 0, 1}, {0, 0, -1}), patch({0.01f, 0, 1}, {0, 0, -1}),
                     patch({0.02f, 0, 1}, {1, 0, 0}), patch({0.03f, 0, 1}, {0, 0, -1})};
    graph.patches[2].points = 5;  // a sliver with a wrong normal between 1 and 3
    graph.patches[2].normal = Vector3f::Zero();
    graph.edges = {{0, 1, 6}, {1, 2, 2}, {2, 3, 4}};
    esf::ConvexityOptions options;
    options.min_segment_points = 20;
    const std::vector<std::uint32_t> segment = esf::convex_segments(graph, options);
    EXPECT_EQ(segment, (std::vector<std::uint32_t>{0, 0, 1, 1}));
}

// Ray-cast organised frames (tests/support/box_scene.hpp): the camera 1.3 m from boxes on a table
// 50 cm below it, looking down at them.
esf::SegmentationOptions options_for(esf::Grouping grouping) {
    esf::SegmentationOptions options;
    options.grouping = grouping;
    options.threads = 1;
    return options;
}

std::size_t objects_found(const esf::test::CastScene& scene, const esf::SegmentationResult& r,
                          int boxes) {
    std::size_t found = 0;
    for (int k = 1; k <= boxes; ++k) {
        std::size_t total = 0;
        for (const int o : scene.owner) total += o == k;
        for (const esf::Cluster& c : r.clusters) {
            std::size_t mine = 0;
            for (const std::uint32_t i : c.indices) mine += scene.owner[i] == k;
            if (10 * mine >= 8 * total && 10 * mine >= 8 * c.indices.size()) ++found;
        }
    }
    return found;
}

TEST(ConvexityGrouping, SplitsStackedAndTouchingBoxesThatEuclideanClusteringJoins) {
    const float table = 0.5f;
    // A box standing on a wider box, and a third box, set back, touching the lower one's side.
    const std::vector<esf::test::Box> boxes = {
        {{-0.10f, table - 0.12f, 1.30f}, {0.06f, table, 1.46f}},
        {{-0.06f, table - 0.22f, 1.34f}, {0.02f, table - 0.12f, 1.42f}},
        {{0.06f, table - 0.08f, 1.34f}, {0.14f, table, 1.42f}},
    };
    const esf::test::CastScene scene = esf::test::cast_boxes(boxes, table);
    const esf::SegmentationResult convex =
        esf::segment_scene(scene.cloud, options_for(esf::Grouping::kConvexity));
    const esf::SegmentationResult euclidean =
        esf::segment_scene(scene.cloud, options_for(esf::Grouping::kEuclidean));
    ASSERT_TRUE(convex.plane_found) << convex.message;
    EXPECT_EQ(objects_found(scene, convex, 3), 3u) << convex.message;
    EXPECT_EQ(convex.clusters.size(), 3u);
    // The stacked pair touches in every view: one Euclidean cluster.
    EXPECT_EQ(euclidean.clusters.size(), 2u);
    EXPECT_EQ(objects_found(scene, euclidean, 3), 1u);
    // The same frame as an unorganised cloud: voxel patches (1.5 cm, coarser than the image
    // tiles) split the stacked pair less surely than the image does, but never join more than
    // Euclidean clustering.
    esf::PointCloud flat = scene.cloud;
    flat.height = 1;
    flat.width = static_cast<std::uint32_t>(flat.points.size());
    const esf::SegmentationResult voxels =
        esf::segment_scene(flat, options_for(esf::Grouping::kConvexity));
    EXPECT_GE(objects_found(scene, voxels, 3), 1u) << voxels.message;
    EXPECT_GE(voxels.clusters.size(), euclidean.clusters.size());
}

TEST(ConvexityGrouping, ApartBoxesAreOneClusterEachWhateverTheGrouping) {
    const float table = 0.5f;
    const std::vector<esf::test::Box> boxes = {
        {{-0.20f, table - 0.15f, 1.3f}, {-0.10f, table, 1.4f}},
        {{0.05f, table - 0.10f, 1.3f}, {0.15f, table, 1.4f}},
    };
    const esf::test::CastScene scene = esf::test::cast_boxes(boxes, table);
    for (const esf::Grouping g : {esf::Grouping::kConvexity, esf::Grouping::kEuclidean}) {
        const esf::SegmentationResult r = esf::segment_scene(scene.cloud, options_for(g));
        EXPECT_EQ(r.clusters.size(), 2u);
        EXPECT_EQ(objects_found(scene, r, 2), 2u);
    }
}

}  // namespace
