#include "esf/segmentation/surface_patches.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <stdexcept>

#include "support/box_scene.hpp"

namespace {

using Eigen::Vector3f;

// A fronto-parallel wall 1 m away, every pixel of a w x h image.
esf::Points wall(std::uint32_t w, std::uint32_t h, float depth = 1.0f) {
    esf::Points points;
    for (std::uint32_t v = 0; v < h; ++v)
        for (std::uint32_t u = 0; u < w; ++u)
            points.emplace_back(0.002f * static_cast<float>(u), 0.002f * static_cast<float>(v),
                                depth);
    return points;
}

std::vector<std::uint32_t> all(std::size_t n) {
    std::vector<std::uint32_t> members(n);
    std::iota(members.begin(), members.end(), 0u);
    return members;
}

TEST(ImagePatches, TilesOfAPlaneAndTheirContacts) {
    const esf::Points points = wall(24, 18);
    esf::SurfacePatchOptions options;
    options.tile_pixels = 6;
    const esf::PatchGraph graph = esf::image_patches(points, 24, 18, all(points.size()), options);
    ASSERT_EQ(graph.patches.size(), 12u);  // 4 x 3 tiles
    for (const esf::SurfacePatch& p : graph.patches) {
        EXPECT_EQ(p.points, 36u);
        ASSERT_TRUE(p.has_normal());
        EXPECT_NEAR(p.normal.z(), -1.0f, 1e-5f);  // towards the viewpoint at the origin
    }
    EXPECT_EQ(graph.patch_of[0], 0u);
    EXPECT_EQ(graph.patch_of[6], 1u);
    EXPECT_NEAR(graph.patches[0].centroid.x(), 0.005f, 1e-6f);  // mean of 0 ... 0.010
    // 4-neighbour tiles: 3 x 3 horizontal + 4 x 2 vertical borders, 6 pixel pairs each.
    ASSERT_EQ(graph.edges.size(), 17u);
    for (const esf::PatchEdge& e : graph.edges) {
        EXPECT_LT(e.a, e.b);
        EXPECT_EQ(e.contacts, 6u);
    }
}

TEST(ImagePatches, DepthJumpSplitsATileAndCutsTheEdge) {
    esf::Points points = wall(6, 6);
    for (std::uint32_t v = 0; v < 6; ++v)
        for (std::uint32_t u = 3; u < 6; ++u) points[v * 6 + u].z() = 1.2f;  // 20 cm behind
    esf::SurfacePatchOptions options;
    options.tile_pixels = 6;
    const esf::PatchGraph graph = esf::image_patches(points, 6, 6, all(points.size()), options);
    ASSERT_EQ(graph.patches.size(), 2u);
    EXPECT_EQ(graph.patches[0].points, 18u);
    EXPECT_TRUE(graph.edges.empty());
    // A 5 mm step at 1 m is continuous: one patch.
    for (Vector3f& p : points)
        if (p.z() > 1.1f) p.z() = 1.005f;
    EXPECT_EQ(esf::image_patches(points, 6, 6, all(points.size()), options).patches.size(), 1u);
}

TEST(ImagePatches, CollinearPatchHasNoNormalAndBadInputIsRefused) {
    const esf::Points points = wall(6, 1);  // one row: collinear
    const esf::PatchGraph graph = esf::image_patches(points, 6, 1, all(6), {});
    ASSERT_EQ(graph.patches.size(), 1u);
    EXPECT_FALSE(graph.patches[0].has_normal());
    EXPECT_THROW(esf::image_patches(points, 5, 1, all(5), {}), std::invalid_argument);
    EXPECT_THROW(esf::image_patches(points, 6, 1, std::vector<std::uint32_t>{3, 2}, {}),
                 std::invalid_argument);
    esf::SurfacePatchOptions bad;
    bad.tile_pixels = 1;
    EXPECT_THROW(esf::image_patches(points, 6, 1, all(6), bad), std::invalid_argument);
    bad = {};
    bad.voxel_size = std::nanf("");
    EXPECT_THROW(esf::voxel_patches(points, all(6), bad), std::invalid_argument);
}

TEST(VoxelPatches, PlaneNormalsAndNeighbours) {
    const esf::Points points = wall(30, 30);  // 6 cm x 6 cm at 2 mm
    esf::SurfacePatchOptions options;
    options.voxel_size = 0.02f;
    const esf::PatchGraph graph = esf::voxel_patches(points, all(points.size()), options);
    ASSERT_EQ(graph.patches.size(), 9u);  // 3 x 3 voxels
    std::size_t total = 0;
    for (const esf::SurfacePatch& p : graph.patches) {
        total += p.points;
        ASSERT_TRUE(p.has_normal());
        EXPECT_NEAR(p.normal.z(), -1.0f, 1e-5f);
    }
    EXPECT_EQ(total, points.size());
    EXPECT_EQ(graph.edges.size(), 20u);  // 12 sharing a side, 8 a corner
    esf::Points far = points;
    far[0].x() = 1e9f;
    EXPECT_THROW(esf::voxel_patches(far, all(far.size()), options), std::invalid_argument);
}

}  // namespace
