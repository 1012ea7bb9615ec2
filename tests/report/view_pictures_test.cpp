// Training views drawn again from their meshes: a box stored in millimetres, trained at a scale
// of 0.001, comes back from ViewRenderer with as many points as training rendered, all of them
// on the box's faces once mapped back through the stored pose (scale included); unknown models
// and missing meshes throw naming them.

#include "esf/report/view_pictures.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "esf/core/error.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"
#include "support/test_meshes.hpp"

namespace fs = std::filesystem;

namespace {

/// A closed box [-50, 50] x [-30, 30] x [0, 200] (millimetres), twelve triangles.
esf::Mesh box_mm() { return esf::test::standing_box(100.0, 60.0, 200.0); }

class ViewPicturesTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("esf_view_pictures_test_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_ / "meshes" / "box");
        esf::write_ply_mesh((dir_ / "meshes" / "box" / "carton.ply").string(), box_mm());
        database_ = (dir_ / "db.sqlite").string();
        esf::TrainingOptions options;
        options.render.level = 0;
        options.render.scale = 0.001;
        options.render.noise = esf::SensorNoise::kNone;
        options.render.distance = 0.8;
        options.render.max_distance.reset();
        options.use_catalog = false;
        options.threads = 2;
        esf::Database db(database_, esf::OpenMode::kWrite);
        esf::train((dir_ / "meshes").string(), db, options);
    }
    void TearDown() override { fs::remove_all(dir_); }

    fs::path dir_;
    std::string database_;
};

TEST_F(ViewPicturesTest, ViewsComeBackOnTheModelsFaces) {
    const esf::Database db(database_, esf::OpenMode::kRead);
    const std::vector<esf::ViewEntry> views = db.views("box", "carton");
    ASSERT_GE(views.size(), 5u);
    esf::ViewRenderer renderer(database_, (dir_ / "meshes").string());
    std::size_t checked = 0;
    for (const esf::ViewEntry& view : views) {
        if (view.points == 0) continue;
        ++checked;
        SCOPED_TRACE("view " + std::to_string(view.index));
        const esf::Points points = renderer.render("box", "carton", view.pose);
        // The same camera as training: the same pixels hit, give or take a silhouette pixel.
        EXPECT_NEAR(static_cast<double>(points.size()), static_cast<double>(view.points),
                    0.02 * static_cast<double>(view.points) + 2.0);
        // Camera -> model (millimetres): every point lies on a face of the box.
        const Eigen::Matrix4d inverse = view.pose.cast<double>().inverse();
        std::size_t off = 0;
        for (const Eigen::Vector3f& p : points) {
            const Eigen::Vector4d m = inverse * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0);
            const double face =
                std::min({std::abs(std::abs(m.x()) - 50.0), std::abs(std::abs(m.y()) - 30.0),
                          std::abs(m.z()), std::abs(m.z() - 200.0)});
            const bool inside = std::abs(m.x()) <= 50.5 && std::abs(m.y()) <= 30.5 &&
                                m.z() >= -0.5 && m.z() <= 200.5;
            off += !(inside && face < 0.5);
        }
        EXPECT_EQ(off, 0u);
        // 0.8 m from the box's centre: depths within its bounding sphere (0.11 m) of that.
        for (const Eigen::Vector3f& p : points) {
            EXPECT_GT(p.z(), 0.8f - 0.12f);
            EXPECT_LT(p.z(), 0.8f + 0.12f);
        }
    }
    EXPECT_GE(checked, 5u);
}

TEST_F(ViewPicturesTest, UnknownModelsAndMissingMeshesThrowNamingThem) {
    const esf::Database db(database_, esf::OpenMode::kRead);
    const esf::ViewEntry view = db.views("box", "carton").front();
    esf::ViewRenderer renderer(database_, (dir_ / "meshes").string());
    try {
        renderer.render("box", "crate", view.pose);
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("no model box/crate"), std::string::npos) << e.what();
    }
    esf::ViewRenderer elsewhere(database_, (dir_ / "nowhere").string());
    try {
        elsewhere.render("box", "carton", view.pose);
        FAIL() << "no exception";
    } catch (const esf::IoError& e) {
        EXPECT_NE(std::string(e.what()).find((dir_ / "nowhere" / "box").string()),
                  std::string::npos)
            << e.what();
    }
}

}  // namespace
