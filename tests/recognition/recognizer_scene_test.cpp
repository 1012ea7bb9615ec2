// The recognizer on scenes: synthetic ones with two objects or none, clusters it cannot
// describe, and a real scene.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/knn_index.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"
#include "support/error_of.hpp"
#include "support/recognizer_fixture.hpp"
#include "support/test_data.hpp"

namespace fs = std::filesystem;

namespace {

using esf::test::kHeldOut;
using esf::test::kSamples;
using esf::test::kShapes;
using esf::test::RecognizerTest;
using esf::test::temp_dir;

// ---- scenes ---------------------------------------------------------------------------------

/// `objects` on a 1.2 m table (world z up) as a Kinect at `camera` sees them.
esf::PointCloud table_scene(const std::vector<esf::SceneObject>& objects,
                            const Eigen::Isometry3d& camera) {
    esf::SceneOptions options;
    options.table_plane = true;
    options.table_half_size = 0.6;
    options.noise = esf::SensorNoise::kKinect;
    options.seed = 3;
    return esf::render_scene(objects, camera, options);
}

TEST_F(RecognizerTest, SyntheticSceneWithTwoObjects) {
    // The mug and the bowl on a table (world z up), seen from 0.9 m at 35 degrees elevation.
    const esf::Mesh& mug = meshes_["mug"];
    const esf::Mesh& bowl = meshes_["bowl"];
    Eigen::Isometry3d mug_pose = Eigen::Isometry3d::Identity();
    mug_pose.translation() = Eigen::Vector3d(0.0, 0.15, 0.0);
    Eigen::Isometry3d bowl_pose = Eigen::Isometry3d::Identity();
    bowl_pose.translation() = Eigen::Vector3d(0.05, -0.15, 0.0);
    const Eigen::Isometry3d camera = esf::look_at({0.75, 0.1, 0.5}, {0, 0, 0.05});
    const esf::PointCloud scene = table_scene({{&mug, mug_pose}, {&bowl, bowl_pose}}, camera);

    for (const int threads : {1, 2}) {
        esf::RecognizerOptions options;
        options.threads = threads;
        const esf::Recognizer recognizer(db_path_, options);
        esf::SegmentationOptions segmentation;
        segmentation.threads = threads;
        // The objects stand apart; convexity grouping cuts the mug's handle off at its joints.
        segmentation.grouping = esf::Grouping::kEuclidean;
        const esf::SceneRecognition result = recognizer.recognize_scene(scene, segmentation);
        EXPECT_TRUE(result.plane_found);
        ASSERT_EQ(result.objects.size(), 2u) << result.message;
        for (const esf::RecognizedObject& o : result.objects) {
            ASSERT_TRUE(o.classified()) << o.error;
            // The object's world position tells which it is.
            const Eigen::Vector3d world = camera.inverse() * o.cluster.centroid.cast<double>();
            const std::string truth = world.y() > 0 ? "mug" : "bowl";
            EXPECT_EQ(o.classification.class_name, truth) << "centroid " << world.transpose();
            EXPECT_EQ(o.classification.neighbours.size(),
                      std::min<std::size_t>(10, recognizer.info().models));
            EXPECT_GT(o.cluster.points.size(), 300u);
        }
    }
}

TEST_F(RecognizerTest, PartsThatOneModelFitsBetterBecomeOneObject) {
    // The mug alone, its handle towards the camera's side: convexity grouping cuts the handle
    // off at its joints; fitted to both parts, the mug explains them, and they become one.
    const esf::Mesh& mug = meshes_["mug"];
    const Eigen::Isometry3d camera = esf::look_at({0.6, 0.3, 0.45}, {0, 0, 0.05});
    const esf::PointCloud scene = table_scene({{&mug, Eigen::Isometry3d::Identity()}}, camera);
    std::size_t mug_points = 0;
    for (const Eigen::Vector3f& p : scene.points)
        mug_points += std::isfinite(p.z()) && (camera.inverse() * p.cast<double>()).z() > 0.01;

    esf::RecognizerOptions apart;
    apart.merge_parts = false;
    const esf::SceneRecognition parts = esf::Recognizer(db_path_, apart).recognize_scene(scene, {});
    ASSERT_GE(parts.objects.size(), 2u) << "the mug is no longer cut at its handle";

    for (const int threads : {1, 2}) {
        esf::RecognizerOptions options;
        options.threads = threads;
        const esf::Recognizer recognizer(db_path_, options);
        ASSERT_TRUE(recognizer.verifies());
        const esf::SceneRecognition result = recognizer.recognize_scene(scene, {});
        ASSERT_EQ(result.objects.size(), 1u) << result.message;
        const esf::RecognizedObject& o = result.objects.front();
        ASSERT_TRUE(o.classified()) << o.error;
        EXPECT_EQ(o.classification.class_name, "mug");
        EXPECT_TRUE(o.classification.verified);
        std::size_t parts_points = 0;
        for (const esf::RecognizedObject& p : parts.objects)
            parts_points += p.cluster.points.size();
        EXPECT_EQ(o.cluster.points.size(), parts_points);
        EXPECT_GT(o.cluster.points.size(), mug_points * 8 / 10);
        EXPECT_EQ(o.cluster.indices.size(), o.cluster.points.size());
        // Measured again as one object: its centroid is its points' mean.
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const Eigen::Vector3f& p : o.cluster.points) mean += p.cast<double>();
        mean /= static_cast<double>(o.cluster.points.size());
        EXPECT_LT((mean - o.cluster.centroid.cast<double>()).norm(), 1e-4);
    }

    // The least share of points a merged fit must explain is a share.
    for (const double bad : {-0.1, 1.5, std::nan("")}) {
        esf::RecognizerOptions options;
        options.merge_min_inliers = bad;
        EXPECT_CONTAINS(MESSAGE_OF(std::invalid_argument, esf::Recognizer(db_path_, options)),
                        "merge_min_inliers");
    }
}

TEST_F(RecognizerTest, APartsOwnModelMayExplainTheUnion) {
    // The mug cut at its handle, seen from two sides where the union's nearest view starts its
    // fit too far off to explain both parts: the body's own fitted mug, moved from where it
    // stood, explains them, and they become one object.
    const esf::Mesh& mug = meshes_["mug"];
    for (const double azimuth : {std::numbers::pi / 3, 3 * std::numbers::pi / 2}) {
        const Eigen::Isometry3d camera =
            esf::look_at({0.7 * std::cos(azimuth), 0.7 * std::sin(azimuth), 0.45}, {0, 0, 0.05});
        const esf::PointCloud scene = table_scene({{&mug, Eigen::Isometry3d::Identity()}}, camera);
        esf::RecognizerOptions options;
        options.merge_parts = false;
        const esf::SceneRecognition parts =
            esf::Recognizer(db_path_, options).recognize_scene(scene, {});
        ASSERT_EQ(parts.objects.size(), 2u) << "the mug is no longer cut at its handle";
        options.merge_parts = true;
        const esf::SceneRecognition result =
            esf::Recognizer(db_path_, options).recognize_scene(scene, {});
        ASSERT_EQ(result.objects.size(), 1u) << "azimuth " << azimuth;
        const esf::RecognizedObject& o = result.objects.front();
        EXPECT_EQ(o.cluster.points.size(),
                  parts.objects[0].cluster.points.size() + parts.objects[1].cluster.points.size());
        const esf::Classification& c = o.classification;
        EXPECT_EQ(c.class_name, "mug");
        EXPECT_TRUE(c.verified);
        ASSERT_TRUE(c.fit.has_value());
        EXPECT_GE(c.fit->inliers, options.merge_min_inliers);
    }
}

TEST(VerificationFrame, TheImageItselfItsPointsAsTheImageOrNone) {
    const esf::CameraIntrinsics camera = esf::CameraIntrinsics::kinect();
    const std::size_t w = static_cast<std::size_t>(camera.width);
    const std::size_t h = static_cast<std::size_t>(camera.height);
    // The camera's own image: used as it is.
    esf::PointCloud image;
    image.width = static_cast<std::uint32_t>(w);
    image.height = static_cast<std::uint32_t>(h);
    image.points.assign(w * h, Eigen::Vector3f::Constant(std::nanf("")));
    for (std::size_t v = 100; v < 120; ++v)
        for (std::size_t u = 200; u < 220; ++u) {
            const float z = 1.0f;
            image.points[v * w + u] = {
                static_cast<float>((static_cast<double>(u) - camera.cx) / camera.fx) * z,
                static_cast<float>((static_cast<double>(v) - camera.cy) / camera.fy) * z, z};
        }
    std::optional<esf::PointCloud> made;
    EXPECT_EQ(esf::verification_frame(image, camera, made), &image);
    EXPECT_FALSE(made.has_value());
    // Its finite points alone: made into that image again.
    esf::PointCloud finite;
    for (const Eigen::Vector3f& p : image.points)
        if (std::isfinite(p.z())) finite.points.push_back(p);
    finite.width = static_cast<std::uint32_t>(finite.points.size());
    finite.height = 1;
    const esf::PointCloud* frame = esf::verification_frame(finite, camera, made);
    ASSERT_NE(frame, nullptr);
    ASSERT_TRUE(made.has_value());
    EXPECT_EQ(frame, &*made);
    EXPECT_EQ(frame->width, image.width);
    EXPECT_EQ(frame->height, image.height);
    EXPECT_TRUE(frame->points[110 * w + 210].isApprox(image.points[110 * w + 210], 1e-5f));
    // An organised cloud of another size: no frame.
    esf::PointCloud small;
    small.width = 4;
    small.height = 2;
    small.points.assign(8, Eigen::Vector3f(0.0f, 0.0f, 1.0f));
    EXPECT_EQ(esf::verification_frame(small, camera, made), nullptr);
    EXPECT_FALSE(made.has_value());
}

/// A 1 m x 1 m table at z = 1 (camera frame, facing the camera) sampled every 5 mm.
esf::Points table_points() {
    esf::Points table;
    for (int i = 0; i < 200; ++i)
        for (int j = 0; j < 200; ++j)
            table.push_back({-0.5f + 0.005f * float(i), -0.5f + 0.005f * float(j), 1.0f});
    return table;
}

TEST_F(RecognizerTest, ClustersThatCannotBeDescribedAreReportedPerObject) {
    esf::Points scene = table_points();
    // A solid block 5 cm above the table (towards the camera: smaller z)...
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j)
            for (int k = 0; k < 10; ++k)
                scene.push_back(
                    {0.2f + 0.005f * float(i), 0.005f * float(j), 0.95f - 0.005f * float(k)});
    // ...two isolated points far from everything...
    scene.push_back({-0.3f, -0.3f, 0.9f});
    scene.push_back({-0.3f, -0.3f, 0.905f});
    // ...and a thin straight wire: one line.
    for (int k = 0; k < 40; ++k) scene.push_back({-0.3f, 0.3f, 0.98f - 0.004f * float(k)});
    esf::SegmentationOptions segmentation;
    segmentation.min_cluster_points = 1;
    segmentation.grouping = esf::Grouping::kEuclidean;  // a solid block: no surface to patch
    const esf::Recognizer recognizer(db_path_);
    const esf::SceneRecognition result = recognizer.recognize_scene(
        esf::PointCloud{scene, static_cast<std::uint32_t>(scene.size()), 1, {}, {}}, segmentation);
    ASSERT_TRUE(result.plane_found);
    ASSERT_EQ(result.objects.size(), 3u) << result.message;
    EXPECT_EQ(result.objects[0].cluster.points.size(), 1000u);
    EXPECT_TRUE(result.objects[0].classified()) << result.objects[0].error;
    EXPECT_EQ(result.objects[1].cluster.points.size(), 40u);
    EXPECT_FALSE(result.objects[1].classified());
    EXPECT_CONTAINS(result.objects[1].error, "esf: ");
    EXPECT_EQ(result.objects[2].cluster.points.size(), 2u);
    EXPECT_FALSE(result.objects[2].classified());
    EXPECT_CONTAINS(result.objects[2].error, "esf: needs at least 3 finite points, got 2");
}

TEST_F(RecognizerTest, SceneWithoutPlaneOrObjectsSaysSo) {
    const esf::Recognizer recognizer(db_path_);
    esf::Points table = table_points();
    const esf::SceneRecognition empty = recognizer.recognize_scene(
        esf::PointCloud{table, static_cast<std::uint32_t>(table.size()), 1, {}, {}});
    EXPECT_TRUE(empty.plane_found);
    EXPECT_TRUE(empty.objects.empty());
    EXPECT_CONTAINS(empty.message, "no objects");

    std::mt19937_64 rng(3);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    esf::Points cloud;
    for (int i = 0; i < 5000; ++i) cloud.push_back({u(rng), u(rng), 2.0f + u(rng)});
    const esf::SceneRecognition none = recognizer.recognize_scene(
        esf::PointCloud{cloud, static_cast<std::uint32_t>(cloud.size()), 1, {}, {}});
    EXPECT_FALSE(none.plane_found);
    EXPECT_TRUE(none.objects.empty());
    EXPECT_CONTAINS(none.message, "no dominant plane");
}

TEST_F(RecognizerTest, RealSceneObjectsAreSegmentedAndClassified) {
    ESF_REQUIRE_DATA("real/scenes/mosd_learn0.pcd");
    const esf::PointCloud scene =
        esf::read_cloud(esf::test::data_file("real/scenes/mosd_learn0.pcd").string());
    ASSERT_EQ(scene.labels.size(), scene.points.size());
    // Labelled objects: label / 10 >= 2 is object label / 10 - 1.
    std::map<std::uint32_t, std::size_t> labelled;
    for (const std::uint32_t l : scene.labels)
        if (l >= 20) ++labelled[l / 10];
    ASSERT_FALSE(labelled.empty());

    const esf::Recognizer recognizer(db_path_);
    const esf::SceneRecognition result = recognizer.recognize_scene(scene);
    ASSERT_TRUE(result.plane_found) << result.message;
    // Every cluster has a class, and most of every labelled object of a fair size lies in one
    // cluster (two touching objects may share one).
    std::map<std::uint32_t, std::size_t> most;  // object -> its points in its best cluster
    for (const esf::RecognizedObject& o : result.objects) {
        EXPECT_TRUE(o.classified()) << o.error;
        EXPECT_TRUE(o.classification.class_name == "mug" || o.classification.class_name == "bowl");
        std::map<std::uint32_t, std::size_t> inside;
        for (const std::uint32_t i : o.cluster.indices) ++inside[scene.labels[i] / 10];
        for (const auto& [object, n] : inside) most[object] = std::max(most[object], n);
    }
    for (const auto& [object, points] : labelled)
        if (points >= 2000) {
            EXPECT_GE(2 * most[object], points) << "object " << object;
        }
}

}  // namespace
