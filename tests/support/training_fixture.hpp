#pragma once
// The training tests' fixtures: a temporary folder per test, small procedural meshes, fast
// training settings and exact database comparisons.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "esf/mesh/mesh.hpp"
#include "esf/training/training.hpp"

namespace esf::test {

namespace fs = std::filesystem;

class TrainingTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("esf_training_test_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    void touch(const std::string& name, const std::string& content = "x") const {
        fs::create_directories((dir_ / name).parent_path());
        std::ofstream(dir_ / name) << content;
    }

    fs::path dir_;
};

// ---- procedural meshes ----------------------------------------------------------------------

inline Mesh box_mesh(float sx, float sy, float sz) {
    Mesh m;
    for (int i = 0; i < 8; ++i)
        m.vertices.emplace_back((i & 1 ? 0.5f : -0.5f) * sx, (i & 2 ? 0.5f : -0.5f) * sy,
                                (i & 4 ? 0.5f : -0.5f) * sz);
    // Two counter-clockwise triangles per face (seen from outside).
    const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) {
        m.triangles.emplace_back(f[0], f[1], f[2]);
        m.triangles.emplace_back(f[0], f[2], f[3]);
    }
    return m;
}

inline Mesh sphere_mesh(float radius, int rings = 12, int segments = 24) {
    Mesh m;
    const float pi = std::numbers::pi_v<float>;
    m.vertices.emplace_back(0.0f, 0.0f, radius);
    for (int r = 1; r < rings; ++r) {
        const float theta = pi * static_cast<float>(r) / static_cast<float>(rings);
        for (int s = 0; s < segments; ++s) {
            const float phi = 2.0f * pi * static_cast<float>(s) / static_cast<float>(segments);
            m.vertices.emplace_back(radius * std::sin(theta) * std::cos(phi),
                                    radius * std::sin(theta) * std::sin(phi),
                                    radius * std::cos(theta));
        }
    }
    m.vertices.emplace_back(0.0f, 0.0f, -radius);
    const int bottom = static_cast<int>(m.vertices.size()) - 1;
    auto at = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
    for (int s = 0; s < segments; ++s) {
        m.triangles.emplace_back(0, at(1, s), at(1, s + 1));
        for (int r = 1; r + 1 < rings; ++r) {
            m.triangles.emplace_back(at(r, s), at(r + 1, s), at(r + 1, s + 1));
            m.triangles.emplace_back(at(r, s), at(r + 1, s + 1), at(r, s + 1));
        }
        m.triangles.emplace_back(bottom, at(rings - 1, s + 1), at(rings - 1, s));
    }
    return m;
}

/// Small, fast settings: the paper's ESF, 20 views (the whole view sphere), a 160x120 camera,
/// 2000 ESF samples.
inline TrainingOptions fast_options() {
    TrainingOptions o;
    o.descriptor = "esf";
    o.render.min_elevation = -90.0;
    o.render.level = 0;
    o.render.camera.width = 160;
    o.render.camera.height = 120;
    o.render.camera.fx = o.render.camera.fy = 131.25;
    o.render.camera.cx = 79.5;
    o.render.camera.cy = 59.5;
    o.render.distance.reset();  // the small camera sees the small test shapes at fill 0.5
    o.render.max_distance.reset();
    o.esf.samples = 2000;
    o.occlusions = 0;  // one signature a view; OccludedCopies... tests the copies
    o.seed = 7;
    o.threads = 2;
    return o;
}

/// Everything a database holds about its models, for exact comparisons.
struct Snapshot {
    std::vector<ModelInfo> models;
    std::vector<std::vector<ViewEntry>> views;
};

inline Snapshot snapshot(const Database& db) {
    Snapshot s;
    s.models = db.models();
    for (const auto& m : s.models) s.views.push_back(db.views(m.category, m.name));
    return s;
}

inline void expect_same(const Snapshot& a, const Snapshot& b) {
    ASSERT_EQ(a.models.size(), b.models.size());
    for (std::size_t i = 0; i < a.models.size(); ++i) {
        SCOPED_TRACE(a.models[i].category + "/" + a.models[i].name);
        EXPECT_EQ(a.models[i].category, b.models[i].category);
        EXPECT_EQ(a.models[i].name, b.models[i].name);
        EXPECT_EQ(a.models[i].status, b.models[i].status);
        EXPECT_EQ(a.models[i].scale, b.models[i].scale);
        EXPECT_EQ(a.models[i].group, b.models[i].group);
        ASSERT_EQ(a.views[i].size(), b.views[i].size());
        for (std::size_t v = 0; v < a.views[i].size(); ++v) {
            EXPECT_EQ(a.views[i][v].index, b.views[i][v].index);
            EXPECT_EQ(a.views[i][v].points, b.views[i][v].points);
            EXPECT_EQ(a.views[i][v].pose, b.views[i][v].pose);
            EXPECT_EQ(a.views[i][v].descriptors, b.views[i][v].descriptors);  // bit-exact
            EXPECT_EQ(a.views[i][v].skip_reason, b.views[i][v].skip_reason);
        }
    }
}

class TrainingRunTest : public TrainingTest {
  protected:
    void SetUp() override {
        TrainingTest::SetUp();
        fs::create_directories(dir_ / "root" / "box");
        fs::create_directories(dir_ / "root" / "ball");
        write_ply_mesh(path("root/box/cube.ply"), box_mesh(0.1f, 0.1f, 0.1f));
        write_ply_mesh(path("root/box/slab.ply"), box_mesh(0.2f, 0.12f, 0.04f));
        write_ply_mesh(path("root/ball/sphere.ply"), sphere_mesh(0.05f));
        write_ply_mesh(path("root/ball/egg.ply"), sphere_mesh(0.04f, 10, 20));
    }
    std::string root() const { return path("root"); }
};

}  // namespace esf::test
