// The scene composer against hand-computed geometry: boxes and cylinders of known size, whose
// truth poses must put every labelled pixel on the model's surface, every object on the table or
// on another, and no two objects in the same space.

#include "esf/render/clutter_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numbers>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/test_meshes.hpp"

namespace {

struct Shape {
    bool box = true;
    Eigen::Vector3d size;  // box: sides; cylinder: (radius, radius, height)
};

// Distance of a model-frame point from the shape's surface.
double surface_distance(const Shape& s, const Eigen::Vector3d& p) {
    if (s.box) {
        const Eigen::Vector3d c(0.0, 0.0, 0.5 * s.size.z());
        const Eigen::Vector3d d = (p - c).cwiseAbs() - 0.5 * s.size;
        const double outside = d.cwiseMax(0.0).norm();
        return outside > 0.0 ? outside : -d.maxCoeff();
    }
    const double radial = std::hypot(p.x(), p.y()) - s.size.x();
    const double axial = std::abs(p.z() - 0.5 * s.size.z()) - 0.5 * s.size.z();
    if (radial > 0.0 || axial > 0.0) return std::hypot(std::max(radial, 0.0), std::max(axial, 0.0));
    return std::min(-radial, -axial);
}

// Whether a model-frame point lies inside the shape by more than `depth`.
bool deep_inside(const Shape& s, const Eigen::Vector3d& p, double depth) {
    if (s.box) {
        const Eigen::Vector3d c(0.0, 0.0, 0.5 * s.size.z());
        return ((p - c).cwiseAbs() - 0.5 * s.size).maxCoeff() < -depth;
    }
    // The 48-gon lies inside the circle by r (1 - cos(pi / 48)).
    const double inner = s.size.x() * std::cos(std::numbers::pi / 48.0);
    return std::hypot(p.x(), p.y()) < inner - depth && p.z() > depth && p.z() < s.size.z() - depth;
}

class ClutterSceneTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto add = [&](const std::string& category, bool box, Eigen::Vector3d size) {
            esf::ClutterModel m;
            m.mesh = box ? esf::test::standing_box(size.x(), size.y(), size.z())
                         : esf::test::standing_cylinder(size.x(), size.z());
            m.category = category;
            m.file = category + "/" + std::to_string(models_.size()) + ".ply";
            models_.push_back(std::move(m));
            shapes_.push_back({box, size});
        };
        add("box", true, {0.20, 0.07, 0.28});
        add("box", true, {0.12, 0.12, 0.06});
        add("box", true, {0.16, 0.10, 0.10});
        add("can", false, {0.033, 0.033, 0.12});
        add("can", false, {0.05, 0.05, 0.09});
        add("cup", false, {0.04, 0.04, 0.10});
    }

    esf::ClutterComposer composer(esf::ClutterOptions options = {}) const {
        options.noise = esf::SensorNoise::kNone;
        return esf::ClutterComposer(models_, options);
    }

    // Every labelled pixel on its object's surface under the truth pose, objects resting and
    // apart (TruthPosesExplainEveryPixel).
    void expect_truth_explains_every_pixel(const esf::ClutterComposer& c) const;

    std::vector<esf::ClutterModel> models_;
    std::vector<Shape> shapes_;
};

TEST_F(ClutterSceneTest, ClassifiesFootprints) {
    const esf::ClutterComposer c = composer();
    for (std::size_t m = 0; m < models_.size(); ++m) {
        EXPECT_EQ(c.boxy(m), shapes_[m].box) << m;
        EXPECT_EQ(c.round(m), !shapes_[m].box) << m;
    }
}

TEST_F(ClutterSceneTest, TypesComeInTurnAndParse) {
    const esf::ClutterComposer c = composer();
    const auto& types = esf::clutter_types();
    for (std::size_t i = 0; i < 20; ++i) EXPECT_EQ(c.type_of(i), types[i % types.size()]);
    for (const esf::ClutterType t : types)
        EXPECT_EQ(esf::parse_enum<esf::ClutterType>(esf::to_string(t)), t);
    EXPECT_THROW(esf::parse_enum<esf::ClutterType>("cluttered"), std::invalid_argument);
}

// Every labelled pixel lies on the surface of its object under the truth pose; table pixels lie
// on z = 0 of the world; objects rest on the table or on another object and never overlap.
void ClutterSceneTest::expect_truth_explains_every_pixel(const esf::ClutterComposer& c) const {
    std::map<esf::ClutterType, int> occluded_objects;
    std::set<std::string> placements;
    for (std::size_t index = 0; index < 21; ++index) {
        const esf::ClutterScene scene = c.compose(index);
        SCOPED_TRACE("scene " + std::to_string(index) + " (" + esf::to_string(scene.type) + ")");
        ASSERT_EQ(scene.cloud.width, 640u);
        ASSERT_EQ(scene.cloud.height, 480u);
        ASSERT_EQ(scene.cloud.labels.size(), scene.cloud.points.size());
        ASSERT_EQ(scene.cloud.rgb.size(), scene.cloud.points.size());
        ASSERT_GE(scene.objects.size(), 2u);
        const Eigen::Isometry3d camera_to_world = scene.world_to_camera.inverse();

        std::map<std::uint32_t, const esf::ClutterObject*> by_label;
        for (const esf::ClutterObject& o : scene.objects) {
            by_label[10 * o.object_id] = &o;
            EXPECT_GE(o.visible, 0.0);
            EXPECT_LE(o.visible, 1.0);
            EXPECT_EQ(o.labelled, o.pixels >= esf::kClutterMinLabelledPixels);
            placements.insert(o.placement);
            if (o.visible < 0.9) ++occluded_objects[scene.type];
        }
        std::map<std::uint32_t, std::size_t> counted;
        for (std::size_t p = 0; p < scene.cloud.points.size(); ++p) {
            const std::uint32_t label = scene.cloud.labels[p];
            const Eigen::Vector3d point = scene.cloud.points[p].cast<double>();
            if (label == 0) continue;
            ASSERT_TRUE(point.allFinite());
            if (label == esf::kClutterTableLabel) {
                EXPECT_NEAR((camera_to_world * point).z(), 0.0, 2e-3);
                continue;
            }
            const auto it = by_label.find(label);
            ASSERT_NE(it, by_label.end()) << "label " << label;
            ++counted[label];
            const esf::ClutterObject& o = *it->second;
            const Eigen::Vector3d model = o.pose.inverse().topRows<3>() * point.homogeneous();
            EXPECT_LT(std::abs(surface_distance(shapes_[o.model], model)), 2e-3)
                << "object " << o.object_id << " at pixel " << p;
        }
        for (const esf::ClutterObject& o : scene.objects)
            if (o.labelled) {
                EXPECT_EQ(counted[10 * o.object_id], o.pixels);
            }

        // Resting and apart: the corners (and rims) of each object in the world.
        std::vector<std::vector<Eigen::Vector3d>> corners(scene.objects.size());
        std::vector<double> tops(scene.objects.size(), 0.0);
        for (std::size_t i = 0; i < scene.objects.size(); ++i) {
            const esf::ClutterObject& o = scene.objects[i];
            const Eigen::Matrix4d to_world = camera_to_world.matrix() * o.pose;
            double low = 1e9;
            for (const Eigen::Vector3f& v : models_[o.model].mesh.vertices) {
                const Eigen::Vector3d w = (to_world * v.cast<double>().homogeneous()).head<3>();
                corners[i].push_back(w);
                low = std::min(low, w.z());
                tops[i] = std::max(tops[i], w.z());
            }
            EXPECT_GE(low, -1e-6) << "object " << o.object_id << " sinks into the table";
            if (o.placement != "stacked") {
                EXPECT_NEAR(low, 0.0, 1e-6) << "object " << o.object_id << " floats";
            }
        }
        for (std::size_t i = 0; i < scene.objects.size(); ++i) {
            if (scene.objects[i].placement != "stacked") continue;
            double low = 1e9;
            for (const Eigen::Vector3d& w : corners[i]) low = std::min(low, w.z());
            bool resting = false;
            for (std::size_t j = 0; j < scene.objects.size(); ++j)
                resting = resting || (j != i && std::abs(tops[j] - low) < 1e-6);
            EXPECT_TRUE(resting) << "object " << scene.objects[i].object_id;
        }
        for (std::size_t i = 0; i < scene.objects.size(); ++i)
            for (std::size_t j = 0; j < scene.objects.size(); ++j) {
                if (i == j) continue;
                const esf::ClutterObject& b = scene.objects[j];
                const Eigen::Matrix4d to_b = b.pose.inverse() * scene.world_to_camera.matrix();
                for (const Eigen::Vector3d& w : corners[i]) {
                    const Eigen::Vector3d q = (to_b * w.homogeneous()).head<3>();
                    EXPECT_FALSE(deep_inside(shapes_[b.model], q, 2e-3))
                        << "object " << scene.objects[i].object_id << " inside " << b.object_id;
                }
            }
    }
    EXPECT_GT(occluded_objects[esf::ClutterType::kOccluded] +
                  occluded_objects[esf::ClutterType::kComplex],
              0);
    EXPECT_TRUE(placements.count("stacked"));
    EXPECT_TRUE(placements.count("leaning"));
}

TEST_F(ClutterSceneTest, TruthPosesExplainEveryPixel) {
    expect_truth_explains_every_pixel(composer());
}

// Objects of other sizes than their models': the truth pose carries the size, so the same
// checks hold in the mesh file's coordinates.
TEST_F(ClutterSceneTest, TruthPosesExplainEveryPixelOfResizedObjects) {
    esf::ClutterOptions options;
    options.size_spread = 0.4;
    expect_truth_explains_every_pixel(composer(options));
}

TEST_F(ClutterSceneTest, SizesSpreadWithinTheirBoundsAndEnterThePose) {
    esf::ClutterOptions options;
    options.seed = 3;
    options.size_spread = 0.25;
    const esf::ClutterComposer spread = composer(options);
    double smallest = 2.0, largest = 0.0;
    for (std::size_t index = 0; index < 14; ++index)
        for (const esf::ClutterObject& o : spread.compose(index).objects) {
            EXPECT_GE(o.size, 1.0 / 1.25 - 1e-12);
            EXPECT_LE(o.size, 1.25 + 1e-12);
            smallest = std::min(smallest, o.size);
            largest = std::max(largest, o.size);
            // The upper-left block is size x rotation (the models are in metres: scale 1).
            const Eigen::Matrix3d linear = o.pose.topLeftCorner<3, 3>();
            EXPECT_NEAR(linear.col(0).norm(), o.size, 1e-9);
            EXPECT_NEAR(
                (linear.transpose() * linear / (o.size * o.size) - Eigen::Matrix3d::Identity())
                    .norm(),
                0.0, 1e-9);
        }
    EXPECT_LT(smallest, 0.9);
    EXPECT_GT(largest, 1.1);

    // Without a spread, every object has its model's size and the scene is the default's.
    options.size_spread = 0.0;
    const esf::ClutterScene none = composer(options).compose(4);
    options = {};
    options.seed = 3;
    const esf::ClutterScene plain = composer(options).compose(4);
    EXPECT_EQ(none.cloud.labels, plain.cloud.labels);
    for (const esf::ClutterObject& o : none.objects) EXPECT_EQ(o.size, 1.0);
}

TEST_F(ClutterSceneTest, CylindricScenesHoldRoundModelsOnly) {
    esf::ClutterOptions options;
    options.types = {esf::ClutterType::kCylindric};
    const esf::ClutterComposer c = composer(options);
    for (std::size_t index = 0; index < 6; ++index)
        for (const esf::ClutterObject& o : c.compose(index).objects)
            EXPECT_FALSE(shapes_[o.model].box) << "scene " << index;
}

TEST_F(ClutterSceneTest, SceneDependsOnlyOnSeedAndIndex) {
    esf::ClutterOptions options;
    options.seed = 7;
    options.noise = esf::SensorNoise::kKinect;
    const esf::ClutterComposer c(models_, options);
    const esf::ClutterScene alone = c.compose(5);
    for (std::size_t i = 0; i < 5; ++i) (void)c.compose(i);
    const esf::ClutterScene after = c.compose(5);
    ASSERT_EQ(alone.cloud.points.size(), after.cloud.points.size());
    EXPECT_EQ(0, std::memcmp(alone.cloud.points.data(), after.cloud.points.data(),
                             alone.cloud.points.size() * sizeof(Eigen::Vector3f)));
    EXPECT_EQ(alone.cloud.labels, after.cloud.labels);
    options.seed = 8;
    const esf::ClutterScene other = esf::ClutterComposer(models_, options).compose(5);
    EXPECT_NE(alone.cloud.labels, other.cloud.labels);
}

TEST_F(ClutterSceneTest, RejectsBadInput) {
    EXPECT_THROW(esf::ClutterComposer({}, {}), std::invalid_argument);
    esf::ClutterOptions far;
    far.min_distance = 2.0;
    far.max_distance = 1.0;
    EXPECT_THROW(esf::ClutterComposer(models_, far), std::invalid_argument);
    for (const double spread : {-0.1, 1.5, std::nan("")}) {
        esf::ClutterOptions sized;
        sized.size_spread = spread;
        EXPECT_THROW(esf::ClutterComposer(models_, sized), std::invalid_argument) << spread;
    }
    std::vector<esf::ClutterModel> huge = {models_[0]};
    for (Eigen::Vector3f& v : huge[0].mesh.vertices) v *= 1000.0f;  // millimetres, not metres
    EXPECT_THROW(esf::ClutterComposer(huge, {}), std::invalid_argument);
    std::vector<esf::ClutterModel> broken = {models_[0]};
    broken[0].mesh.triangles.emplace_back(0, 1, 99);
    EXPECT_THROW(esf::ClutterComposer(broken, {}), std::invalid_argument);
}

}  // namespace
