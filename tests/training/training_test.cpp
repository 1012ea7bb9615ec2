#include "esf/training/training.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "esf/core/error.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/mesh/mesh.hpp"
#include "support/error_of.hpp"
#include "support/recursive_collada.hpp"
#include "support/require_baselines.hpp"

namespace esf {
namespace {

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

using esf::test::error_of;

// ---- procedural meshes ----------------------------------------------------------------------

Mesh box_mesh(float sx, float sy, float sz) {
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

Mesh sphere_mesh(float radius, int rings = 12, int segments = 24) {
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
TrainingOptions fast_options() {
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
    o.seed = 7;
    o.threads = 2;
    return o;
}

// KilledProcessResumesToTheSameDatabase runs this test binary again as a training process and
// kills it with SIGKILL. In that process, ESF_TRAINING_TEST_CHILD="ROOT DB MARKER" makes this
// object train ROOT into DB (creating MARKER after the first model is committed) and exit before
// any test runs.
struct TrainingChild {
    TrainingChild() {
        const char* spec = std::getenv("ESF_TRAINING_TEST_CHILD");
        if (!spec || !*spec) return;
        std::istringstream in(spec);
        std::string root, db_path, marker;
        in >> root >> db_path >> marker;
        try {
            Database db(db_path, OpenMode::kWrite);
            TrainingOptions o = fast_options();
            o.threads = 1;
            o.progress = [&](const TrainingProgress& p) {
                if (p.models_done == 1) std::ofstream(marker) << "1";
            };
            train(root, db, o);
        } catch (...) {
            _exit(3);
        }
        _exit(0);
    }
};
const TrainingChild training_child;

/// Everything a database holds about its models, for exact comparisons.
struct Snapshot {
    std::vector<ModelInfo> models;
    std::vector<std::vector<ViewEntry>> views;
};

Snapshot snapshot(const Database& db) {
    Snapshot s;
    s.models = db.models();
    for (const auto& m : s.models) s.views.push_back(db.views(m.category, m.name));
    return s;
}

void expect_same(const Snapshot& a, const Snapshot& b) {
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

// ---- finding models, catalogs, seeds (no rendering) -----------------------------------------

TEST_F(TrainingTest, FindModelsListsCategoryFoldersSorted) {
    touch("root/mug/b.ply");
    touch("root/mug/a.OBJ");
    touch("root/box/z.stl");
    touch("root/box/notes.txt");    // not a mesh
    touch("root/box/.hidden.ply");  // hidden
    touch("root/.trash/x.ply");     // hidden folder
    touch("root/top.ply");          // not in a category folder
    touch("root/catalog.csv");
    touch("root/box/deeper/y.ply");  // too deep
    const auto models = find_models(path("root"));
    ASSERT_EQ(models.size(), 3u);
    EXPECT_EQ(models[0].category, "box");
    EXPECT_EQ(models[0].name, "z");
    EXPECT_EQ(models[0].file, "box/z.stl");
    EXPECT_EQ(models[0].path, path("root/box/z.stl"));
    EXPECT_EQ(models[1].file, "mug/a.OBJ");
    EXPECT_EQ(models[1].name, "a");
    EXPECT_EQ(models[2].file, "mug/b.ply");
}

TEST_F(TrainingTest, FindModelsErrors) {
    EXPECT_EQ(error_of<IoError>([&] { find_models(path("nowhere")); }),
              path("nowhere") + ": no such folder");
    touch("file.txt");
    EXPECT_EQ(error_of<IoError>([&] { find_models(path("file.txt")); }),
              path("file.txt") + ": not a folder");
    touch("root/mug/a.ply");
    touch("root/mug/a.obj");
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { find_models(path("root")); }),
                    "two meshes share the model name 'mug/a': mug/a.obj and mug/a.ply");
}

TEST_F(TrainingTest, CatalogParsesQuotedFields) {
    touch("catalog.csv",
          "file,category,source,model,group,extent,metric,licence,note\r\n"
          "box/a.obj,box,kit,a,fam,0.0722,no,KIT,\"hexagonal, \"\"prism\"\" box\"\r\n"
          "\n"
          "mug/b.ply,mug,ycb,b,b,0.1,yes,CC,\"two\nlines\"\n"
          "mug/c.ply,mug,ycb,c,c,,,CC,\n");
    const Catalog c = read_catalog(path("catalog.csv"));
    ASSERT_EQ(c.entries.size(), 3u);
    EXPECT_EQ(c.entries[0].file, "box/a.obj");
    EXPECT_EQ(c.entries[0].group, "fam");
    EXPECT_EQ(c.entries[0].extent, 0.0722);
    EXPECT_FALSE(c.entries[0].metric);
    EXPECT_TRUE(c.entries[1].metric);
    EXPECT_EQ(c.entries[2].extent, 0.0);  // unknown
    EXPECT_TRUE(c.entries[2].metric);     // empty means metric
    EXPECT_EQ(c.find("mug/b.ply"), &c.entries[1]);
    EXPECT_EQ(c.find("mug/x.ply"), nullptr);
}

TEST_F(TrainingTest, CatalogErrorsNameFileAndLine) {
    const std::string p = path("catalog.csv");
    touch("catalog.csv", "category,group\nbox,a\n");
    EXPECT_EQ(error_of<IoError>([&] { read_catalog(p); }), p + ":1: header has no 'file' column");
    touch("catalog.csv", "file,extent\nbox/a.obj,0.1\nbox/b.obj,big\n");
    EXPECT_EQ(error_of<IoError>([&] { read_catalog(p); }), p + ":3: extent 'big' is not a size");
    touch("catalog.csv", "file,extent\nbox/a.obj,0.1,extra\n");
    EXPECT_EQ(error_of<IoError>([&] { read_catalog(p); }), p + ":2: 3 fields, the header has 2");
    touch("catalog.csv", "file,metric\nbox/a.obj,maybe\n");
    EXPECT_EQ(error_of<IoError>([&] { read_catalog(p); }),
              p + ":2: metric 'maybe' is not yes or no");
    touch("catalog.csv", "file,note\nbox/a.obj,\"open\n");
    EXPECT_EQ(error_of<IoError>([&] { read_catalog(p); }), p + ":2: unterminated quoted field");
    // A UTF-8 byte order mark (spreadsheets write one) and CRLF line ends are accepted.
    touch("catalog.csv",
          "\xEF\xBB\xBF"
          "file,extent\r\nbox/a.obj,0.1\r\n");
    const Catalog bom = read_catalog(p);
    ASSERT_EQ(bom.entries.size(), 1u);
    EXPECT_EQ(bom.entries[0].file, "box/a.obj");
    EXPECT_EQ(bom.entries[0].extent, 0.1);
    touch("catalog.csv", "");
    EXPECT_EQ(error_of<IoError>([&] { read_catalog(p); }),
              p + ": empty catalog (expected a header line)");
    EXPECT_EQ(error_of<IoError>([&] { read_catalog(path("none.csv")); }),
              path("none.csv") + ": cannot open catalog");
}

TEST_F(TrainingTest, TypicalExtentIsTheMedianOfMetricModels) {
    Catalog c;
    c.entries = {{"mug/a.ply", "mug", "a", 0.10, true},  {"mug/b.ply", "mug", "b", 0.14, true},
                 {"mug/c.ply", "mug", "c", 0.04, false},  // non-metric: not counted
                 {"can/a.ply", "can", "a", 0.10, true},  {"can/b.ply", "can", "b", 0.12, true},
                 {"can/c.ply", "can", "c", 0.30, true}};
    EXPECT_DOUBLE_EQ(typical_extent(c, "mug"), 0.12);    // (0.10 + 0.14) / 2
    EXPECT_DOUBLE_EQ(typical_extent(c, "can"), 0.12);    // middle of three
    EXPECT_DOUBLE_EQ(typical_extent(c, "glass"), 0.12);  // table
    EXPECT_DOUBLE_EQ(typical_extent(c, "spray"), 0.20);  // table
    EXPECT_DOUBLE_EQ(typical_extent(c, "widget"), kDefaultTypicalExtent);
}

TEST(TrainingSeeds, DependOnNameAndIndexOnly) {
    EXPECT_EQ(model_seed(1, "mug", "a"), model_seed(1, "mug", "a"));
    EXPECT_NE(model_seed(1, "mug", "a"), model_seed(2, "mug", "a"));
    EXPECT_NE(model_seed(1, "mug", "a"), model_seed(1, "mug", "b"));
    EXPECT_NE(model_seed(1, "mug", "a"), model_seed(1, "cup", "a"));
    EXPECT_NE(model_seed(1, "ab", "c"), model_seed(1, "a", "bc"));
    const auto s = model_seed(1, "mug", "a");
    EXPECT_EQ(view_seed(s, 3), view_seed(s, 3));
    EXPECT_NE(view_seed(s, 3), view_seed(s, 4));
    EXPECT_NE(view_seed(s, 0), s);
}

TEST(TrainingSettings, DefaultsAreEsfAnglesFromAboveAtTableTopDistances) {
    const TrainingOptions o;
    EXPECT_EQ(o.descriptor, "esf-angles");
    const Settings s = training_settings(o, false);
    EXPECT_EQ(s.at("descriptor"), SettingValue(std::string("esf-angles")));
    EXPECT_EQ(s.at("descriptor_version"),
              SettingValue(std::int64_t{kEsfVersion * 100 + kSurfaceAnglesVersion}));
    EXPECT_EQ(s.at("descriptor_dimension"), SettingValue(std::int64_t{kEsfAnglesSize}));
    EXPECT_EQ(s.at("descriptor_angles_weight"), SettingValue(kEsfAnglesWeight));
    EXPECT_EQ(s.at("camera_distance"), SettingValue(0.6));
    EXPECT_EQ(s.at("camera_max_distance"), SettingValue(1.2));
    EXPECT_EQ(s.at("camera_min_elevation"), SettingValue(0.0));
    EXPECT_EQ(s.at("camera_max_elevation"), SettingValue(90.0));
    // A largest distance at or below the distance draws nothing: stored as none.
    TrainingOptions fixed;
    fixed.render.max_distance = 0.6;
    EXPECT_EQ(training_settings(fixed, false).at("camera_max_distance"),
              SettingValue(std::string("none")));
}

TEST(TrainingSettings, RecordEverythingThatChangesTheData) {
    TrainingOptions o;
    o.descriptor = "esf";
    o.seed = 42;
    o.esf.samples = 1234;
    const Settings s = training_settings(o, true);
    EXPECT_EQ(s.at("descriptor"), SettingValue(std::string("esf")));
    EXPECT_EQ(s.at("descriptor_version"), SettingValue(std::int64_t{kEsfVersion}));
    EXPECT_EQ(s.at("descriptor_dimension"), SettingValue(std::int64_t{640}));
    EXPECT_EQ(s.at("seed"), SettingValue(std::int64_t{42}));
    EXPECT_EQ(s.at("esf_samples"), SettingValue(std::int64_t{1234}));
    EXPECT_EQ(s.at("esf_grid_size"), SettingValue(std::int64_t{64}));
    EXPECT_EQ(s.at("view_sphere_level"), SettingValue(std::int64_t{1}));
    EXPECT_EQ(s.at("camera_fx"), SettingValue(525.0));
    EXPECT_EQ(s.at("fill_fraction"), SettingValue(0.5));
    EXPECT_EQ(s.at("noise"), SettingValue(std::string("kinect")));
    EXPECT_EQ(s.at("min_points"), SettingValue(std::int64_t{50}));
    EXPECT_EQ(s.at("rescale_non_metric"), SettingValue(std::string("category_extent")));
    o.seed = ~std::uint64_t{0};  // beyond int64: kept exactly as text
    EXPECT_EQ(training_settings(o, false).at("seed"),
              SettingValue(std::string("18446744073709551615")));
}

TEST(TrainingSettings, BaselinesStoreWhatQueriesAreDescribedWith) {
    TrainingOptions o;
    o.seed = 42;
    o.descriptor = "vfh";
    o.descriptor_options.leaf_factor = 2.5f;
    o.descriptor_options.remove_outliers = false;
    const Settings s = training_settings(o, false);
    EXPECT_EQ(s.at("descriptor"), SettingValue(std::string("vfh")));
    EXPECT_EQ(s.at("descriptor_version"), SettingValue(std::int64_t{kBaselineDescriptorVersion}));
    EXPECT_EQ(s.at("descriptor_dimension"), SettingValue(std::int64_t{308}));
    EXPECT_EQ(s.at("descriptor_samples"), SettingValue(std::int64_t{20000}));
    EXPECT_EQ(s.at("descriptor_leaf_factor"), SettingValue(2.5));
    EXPECT_EQ(s.at("descriptor_normal_radius_factor"), SettingValue(3.0));
    EXPECT_EQ(s.at("descriptor_remove_outliers"), SettingValue(std::int64_t{0}));
    EXPECT_EQ(s.at("seed"), SettingValue(std::int64_t{42}));
    EXPECT_EQ(s.count("esf_samples"), 0u);  // ESF's options do not apply
    // Everything about the views is the same as for esf.
    TrainingOptions e = o;
    e.descriptor = "esf";
    const Settings esf = training_settings(e, false);
    for (const auto& [key, value] : esf)
        if (key.rfind("descriptor", 0) != 0 && key.rfind("esf_", 0) != 0) {
            EXPECT_EQ(s.at(key), value) << key;
        }
    o.descriptor = "sdvs";
    EXPECT_EQ(training_settings(o, false).at("descriptor_dimension"),
              SettingValue(std::int64_t{192}));
    o.descriptor = "fpfh";
    const std::string message =
        error_of<std::invalid_argument>([&] { training_settings(o, false); });
    EXPECT_CONTAINS(message, "unknown descriptor 'fpfh'");
    EXPECT_CONTAINS(message, "esf, esf-angles, pcl-esf, sdvs, d2, vfh, cvfh, our-cvfh, gasd, shot");
}

TEST_F(TrainingTest, BadOptionsAndEmptyRootsAreRejected) {
    Database db(path("db.sqlite"), OpenMode::kWrite);
    touch("empty/mug/readme.txt");
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(path("empty"), db); }),
                    path("empty") + ": no meshes found");
    TrainingOptions o = fast_options();
    o.min_points = 2;
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(path("empty"), db, o); }),
                    "min_points must be >= 3");
    o = fast_options();
    o.esf.samples = 0;
    EXPECT_NE(error_of<std::invalid_argument>([&] { train(path("empty"), db, o); }),
              "(no exception of the expected type)");
    o = fast_options();
    o.descriptor = "fpfh";
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(path("empty"), db, o); }),
                    "unknown descriptor 'fpfh' (valid: esf, esf-angles, pcl-esf, sdvs, d2, vfh");
    o = fast_options();
    o.descriptor = "vfh";
    o.descriptor_options.normal_radius_factor = 0.0f;
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(path("empty"), db, o); }),
                    "normal_radius_factor must be finite and > 0");
    o = fast_options();
    o.threads = -1;
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(path("empty"), db, o); }),
                    "thread count must be >= 0");
    EXPECT_TRUE(db.models().empty());
    EXPECT_TRUE(db.settings().empty());  // nothing written for a run that never started
}

// ---- training (renders small procedural meshes) ---------------------------------------------

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

TEST_F(TrainingRunTest, StoresEveryViewAndTheSettings) {
    Database db(path("db.sqlite"), OpenMode::kWrite);
    std::vector<TrainingProgress> calls;
    TrainingOptions o = fast_options();
    o.progress = [&](const TrainingProgress& p) { calls.push_back(p); };
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_total, 4u);
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.models_failed, 0u);
    EXPECT_EQ(r.views + r.views_skipped, 4u * 20u);

    ASSERT_EQ(calls.size(), 5u);  // once at the start, once per model
    EXPECT_EQ(calls[0].models_done, 0u);
    EXPECT_EQ(calls[0].model, "");
    EXPECT_EQ(calls[1].model, "ball/egg");  // sorted order
    EXPECT_EQ(calls[4].model, "box/slab");
    EXPECT_EQ(calls[4].models_done, 4u);
    EXPECT_EQ(calls[4].views, r.views);

    const auto summary = db.summary();
    EXPECT_EQ(summary.models, 4u);
    EXPECT_EQ(summary.views, r.views);
    EXPECT_EQ(summary.skipped_views, r.views_skipped);
    EXPECT_EQ(db.settings(), training_settings(o, false));
    EXPECT_EQ(db.descriptor_kinds(), (std::vector<DescriptorKind>{{"esf", kEsfVersion, 640}}));
    for (const auto& m : db.models()) {
        EXPECT_EQ(m.group, m.name);  // no catalog: every model its own group
        EXPECT_EQ(m.scale, 1.0);
        for (const auto& v : db.views(m.category, m.name)) {
            if (v.skipped()) continue;
            ASSERT_EQ(v.descriptors.size(), 640u);
            double sum = 0.0;
            for (float x : v.descriptors) sum += x;
            EXPECT_NEAR(sum, 1.0, 1e-4);  // an ESF histogram sums to one
            EXPECT_GE(v.points, o.min_points);
            // The pose is rigid.
            const Eigen::Matrix3f rot = v.pose.topLeftCorner<3, 3>();
            EXPECT_TRUE((rot * rot.transpose()).isIdentity(1e-4f));
        }
    }
    const DescriptorMatrix matrix = db.load_descriptors();
    EXPECT_EQ(matrix.rows(), r.views);
    EXPECT_EQ(matrix.categories, (std::vector<std::string>{"ball", "box"}));
}

TEST_F(TrainingRunTest, ResultDoesNotDependOnThreadCount) {
    TrainingOptions o = fast_options();
    o.threads = 1;
    Database one(path("one.sqlite"), OpenMode::kWrite);
    train(root(), one, o);
    o.threads = 3;
    Database three(path("three.sqlite"), OpenMode::kWrite);
    train(root(), three, o);
    expect_same(snapshot(one), snapshot(three));
}

TEST_F(TrainingRunTest, InterruptedRunResumesToTheSameDatabase) {
    const TrainingOptions o = fast_options();
    Database full(path("full.sqlite"), OpenMode::kWrite);
    train(root(), full, o);

    struct Killed {};
    const std::string db_path = path("resumed.sqlite");
    {
        Database db(db_path, OpenMode::kWrite);
        TrainingOptions killing = o;
        killing.progress = [](const TrainingProgress& p) {
            if (p.models_done == 2) throw Killed{};  // as if killed after the second commit
        };
        EXPECT_THROW(train(root(), db, killing), Killed);
        EXPECT_EQ(db.summary().models, 2u);
    }
    Database db(db_path, OpenMode::kWrite);
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_existing, 2u);
    EXPECT_EQ(r.models_trained, 2u);
    expect_same(snapshot(full), snapshot(db));
    // Nothing left to do the third time.
    const TrainingResult again = train(root(), db, o);
    EXPECT_EQ(again.models_existing, 4u);
    EXPECT_EQ(again.models_trained, 0u);
    expect_same(snapshot(full), snapshot(db));
}

TEST_F(TrainingRunTest, NewModelsAreAddedWithoutChangingOthers) {
    const TrainingOptions o = fast_options();
    Database full(path("full.sqlite"), OpenMode::kWrite);
    train(root(), full, o);

    fs::rename(path("root/box"), path("later_box"));
    Database db(path("grown.sqlite"), OpenMode::kWrite);
    EXPECT_EQ(train(root(), db, o).models_trained, 2u);
    fs::rename(path("later_box"), path("root/box"));
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_existing, 2u);
    EXPECT_EQ(r.models_trained, 2u);
    expect_same(snapshot(full), snapshot(db));
}

TEST_F(TrainingRunTest, OtherSettingsAreRefusedOnResume) {
    Database db(path("db.sqlite"), OpenMode::kWrite);
    TrainingOptions o = fast_options();
    o.progress = [](const TrainingProgress& p) {
        if (p.models_done == 1) throw std::runtime_error("stop");
    };
    EXPECT_THROW(train(root(), db, o), std::runtime_error);
    o.progress = nullptr;
    o.seed = 8;
    o.esf.samples = 3000;
    const std::string message = error_of<std::invalid_argument>([&] { train(root(), db, o); });
    EXPECT_CONTAINS(message, path("db.sqlite") + ": database was trained with other settings: ");
    EXPECT_CONTAINS(message, "esf_samples 3000 (database: 2000)");
    EXPECT_CONTAINS(message, "seed 8 (database: 7)");
    EXPECT_EQ(db.summary().models, 1u);  // untouched
    o = fast_options();
    o.render.level = 1;
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(root(), db, o); }),
                    "view_sphere_level 1 (database: 0)");
}

// ---- baseline descriptors ---------------------------------------------------------------------

TrainingOptions baseline_options(const std::string& descriptor) {
    TrainingOptions o = fast_options();
    o.descriptor = descriptor;
    return o;
}

/// Sums of each `dimension`-float signature of a view.
std::vector<double> signature_sums(const std::vector<float>& descriptors, std::size_t dimension) {
    std::vector<double> sums(descriptors.size() / dimension, 0.0);
    for (std::size_t i = 0; i < descriptors.size(); ++i) sums[i / dimension] += descriptors[i];
    return sums;
}

TEST_F(TrainingRunTest, BaselinesDescribeTheViewsOfTheEsfDatabase) {
    ESF_REQUIRE_BASELINES();
    Database esf_db(path("esf.sqlite"), OpenMode::kWrite);
    train(root(), esf_db, fast_options());
    const Snapshot esf = snapshot(esf_db);

    for (const std::string name : {"vfh", "cvfh"}) {
        SCOPED_TRACE(name);
        Database db(path(name + ".sqlite"), OpenMode::kWrite);
        const TrainingResult r = train(root(), db, baseline_options(name));
        EXPECT_EQ(r.models_trained, 4u);
        EXPECT_EQ(r.views + r.views_skipped, 80u);
        EXPECT_GT(r.views, 60u);
        EXPECT_EQ(db.descriptor_kinds(),
                  (std::vector<DescriptorKind>{{name, kBaselineDescriptorVersion, 308}}));
        EXPECT_EQ(db.settings(), training_settings(baseline_options(name), false));

        const Snapshot s = snapshot(db);
        ASSERT_EQ(s.models.size(), esf.models.size());
        std::size_t signatures = 0, multi = 0;
        for (std::size_t m = 0; m < s.models.size(); ++m) {
            SCOPED_TRACE(s.models[m].name);
            EXPECT_EQ(s.models[m].name, esf.models[m].name);
            EXPECT_EQ(s.models[m].scale, esf.models[m].scale);
            ASSERT_EQ(s.views[m].size(), 20u);
            for (std::size_t v = 0; v < s.views[m].size(); ++v) {
                const ViewEntry& view = s.views[m][v];
                const ViewEntry& same = esf.views[m][v];
                // The same rendering: index, point count and pose bit for bit.
                EXPECT_EQ(view.index, same.index);
                EXPECT_EQ(view.points, same.points);
                EXPECT_EQ(view.pose, same.pose);
                if (same.skipped()) {
                    EXPECT_TRUE(view.skipped());  // too few points for both
                }
                if (view.skipped()) {
                    EXPECT_FALSE(view.skip_reason.empty());
                    continue;
                }
                ASSERT_EQ(view.descriptors.size() % 308, 0u);
                const auto sums = signature_sums(view.descriptors, 308);
                ASSERT_GE(sums.size(), 1u);
                if (name == "vfh") {
                    EXPECT_EQ(sums.size(), 1u);
                }
                for (const double sum : sums) EXPECT_NEAR(sum, 1.0, 1e-4);
                for (const float x : view.descriptors) EXPECT_GE(x, 0.0f);
                signatures += sums.size();
                multi += sums.size() > 1;
            }
        }
        const DescriptorMatrix matrix = db.load_descriptors();
        EXPECT_EQ(matrix.kind.name, name);
        EXPECT_EQ(matrix.rows(), signatures);  // every signature is a row
        if (name == "cvfh") {
            EXPECT_GT(multi, 0u) << "no view of a box has several regions";
        }
    }
}

TEST_F(TrainingRunTest, BaselineViewsAreReproducedFromTheStoredSettings) {
    ESF_REQUIRE_BASELINES();
    // A query described with the settings the database stores (what Recognizer's query_setup()
    // reads) matches the stored descriptor of the same view exactly, and its L1 nearest
    // neighbour is that view.
    Database db(path("vfh.sqlite"), OpenMode::kWrite);
    const TrainingOptions o = baseline_options("vfh");
    train(root(), db, o);
    const Settings settings = db.settings();
    DescriptorOptions query;
    query.leaf_factor = static_cast<float>(std::get<double>(settings.at("descriptor_leaf_factor")));
    query.normal_radius_factor =
        static_cast<float>(std::get<double>(settings.at("descriptor_normal_radius_factor")));
    query.remove_outliers = std::get<std::int64_t>(settings.at("descriptor_remove_outliers")) == 1;
    query.samples = static_cast<int>(std::get<std::int64_t>(settings.at("descriptor_samples")));
    const auto vfh = make_descriptor(std::get<std::string>(settings.at("descriptor")), query);

    RenderOptions render = o.render;
    render.seed = model_seed(o.seed, "box", "slab");
    const MeshRenderer renderer(load_mesh(path("root/box/slab.ply")), render);
    const auto stored = db.views("box", "slab");
    const DescriptorMatrix matrix = db.load_descriptors();
    int checked = 0;
    for (const std::size_t v : {std::size_t{3}, std::size_t{11}}) {
        if (stored[v].skipped()) continue;
        const std::vector<Signature> described = vfh->compute(renderer.render_view(v).points);
        ASSERT_EQ(described.size(), 1u);
        EXPECT_EQ(described[0], stored[v].descriptors);  // bit-exact
        std::size_t best = 0;
        double best_distance = std::numeric_limits<double>::infinity();
        for (std::size_t row = 0; row < matrix.rows(); ++row) {
            double d = 0.0;
            for (std::size_t i = 0; i < 308; ++i)
                d += std::abs(double(matrix.row(row)[i]) - double(described[0][i]));
            if (d < best_distance) best_distance = d, best = row;
        }
        const DescriptorRow& nearest = matrix.row_info[best];
        EXPECT_EQ(matrix.categories[nearest.category], "box");
        EXPECT_EQ(matrix.models[nearest.model].name, "slab");
        EXPECT_EQ(nearest.view_index, static_cast<int>(v));
        EXPECT_EQ(best_distance, 0.0);
        ++checked;
    }
    EXPECT_GT(checked, 0);
}

TEST_F(TrainingRunTest, BaselineDatabasesResumeAndRefuseAnotherDescriptor) {
    ESF_REQUIRE_BASELINES();
    const TrainingOptions o = baseline_options("vfh");
    Database full(path("full.sqlite"), OpenMode::kWrite);
    train(root(), full, o);

    Database db(path("resumed.sqlite"), OpenMode::kWrite);
    TrainingOptions stopping = o;
    stopping.threads = 1;  // and another thread count
    stopping.progress = [](const TrainingProgress& p) {
        if (p.models_done == 2) throw std::runtime_error("stop");
    };
    EXPECT_THROW(train(root(), db, stopping), std::runtime_error);
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_existing, 2u);
    EXPECT_EQ(r.models_trained, 2u);
    expect_same(snapshot(full), snapshot(db));  // vfh is deterministic: bit-exact

    // Another descriptor into it, or vfh into an esf database: refused, naming both.
    std::string message =
        error_of<std::invalid_argument>([&] { train(root(), db, baseline_options("cvfh")); });
    EXPECT_CONTAINS(message, path("resumed.sqlite") + ": database holds vfh descriptors, not cvfh");
    EXPECT_CONTAINS(message, "(setting descriptor cvfh, database: vfh)");
    message = error_of<std::invalid_argument>([&] { train(root(), db, fast_options()); });
    EXPECT_CONTAINS(message, "database holds vfh descriptors, not esf");
    Database esf_db(path("esf.sqlite"), OpenMode::kWrite);
    TrainingOptions one_model = fast_options();
    one_model.progress = [](const TrainingProgress& p) {
        if (p.models_done == 1) throw std::runtime_error("stop");
    };
    EXPECT_THROW(train(root(), esf_db, one_model), std::runtime_error);
    message = error_of<std::invalid_argument>([&] { train(root(), esf_db, o); });
    EXPECT_CONTAINS(message, "database holds esf descriptors, not vfh");
    EXPECT_EQ(esf_db.summary().models, 1u);  // untouched
    EXPECT_EQ(db.descriptor_kinds().size(), 1u);

    // Other baseline options are differences like any other.
    TrainingOptions other = o;
    other.descriptor_options.leaf_factor = 2.0f;
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(root(), db, other); }),
                    "descriptor_leaf_factor 2 (database: 3)");
}

TEST_F(TrainingRunTest, ViewsABaselineCannotDescribeAreSkippedAndCounted) {
    ESF_REQUIRE_BASELINES();
    // With a leaf of 40 mesh resolutions, the voxel grid leaves a handful of points, fewer than
    // the baseline preprocessing needs: every view is skipped with the descriptor's reason.
    TrainingOptions o = baseline_options("vfh");
    o.descriptor_options.leaf_factor = 40.0f;
    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.models_failed, 0u);
    EXPECT_EQ(r.views + r.views_skipped, 80u);
    EXPECT_GT(r.views_skipped, 0u);
    std::size_t described_by_vfh = 0;
    for (const auto& m : db.models())
        for (const auto& v : db.views(m.category, m.name))
            if (v.skipped() && v.skip_reason.rfind("vfh: ", 0) == 0) ++described_by_vfh;
    EXPECT_GT(described_by_vfh, 0u);
    EXPECT_EQ(db.summary().skipped_views, r.views_skipped);
}

TEST_F(TrainingRunTest, BrokenMeshesAreStoredAsFailedAndRetried) {
    touch("root/box/broken.ply", "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n");
    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, fast_options());
    EXPECT_EQ(r.models_total, 5u);
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.models_failed, 1u);
    ASSERT_EQ(r.failures.size(), 1u);
    EXPECT_EQ(r.failures[0].model, "box/broken");
    EXPECT_CONTAINS(r.failures[0].error, "broken.ply");
    EXPECT_EQ(db.model_status("box", "broken"), ModelStatus::kFailed);
    EXPECT_EQ(db.summary().failed_models, 1u);

    // Fixed file: the next run retries it and stores it.
    write_ply_mesh(path("root/box/broken.ply"), box_mesh(0.05f, 0.1f, 0.15f));
    const TrainingResult again = train(root(), db, fast_options());
    EXPECT_EQ(again.models_existing, 4u);
    EXPECT_EQ(again.models_trained, 1u);
    EXPECT_EQ(db.model_status("box", "broken"), ModelStatus::kComplete);
    EXPECT_EQ(db.summary().failed_models, 0u);
}

TEST_F(TrainingRunTest, AMeshThatCrashesTheImporterFailsAloneAndTrainingGoesOn) {
    touch("root/box/recursive.dae", test::recursive_collada());
    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, fast_options());
    EXPECT_EQ(r.models_total, 5u);
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.models_failed, 1u);
    ASSERT_EQ(r.failures.size(), 1u);
    EXPECT_EQ(r.failures[0].model, "box/recursive");
    EXPECT_EQ(r.failures[0].error.rfind(path("root/box/recursive.dae") + ": the mesh importer ", 0),
              0u)
        << r.failures[0].error;
    EXPECT_EQ(db.model_status("box", "recursive"), ModelStatus::kFailed);
    EXPECT_EQ(db.model_status("box", "cube"), ModelStatus::kComplete);
}

TEST_F(TrainingRunTest, SymbolicLinkLoopsAreReportedAndTrainingGoesOn) {
    fs::create_symlink("loop.ply", dir_ / "root" / "box" / "loop.ply");  // points at itself
    fs::create_symlink("looping", dir_ / "root" / "looping");            // a category folder too
    const auto models = find_models(root());
    ASSERT_EQ(models.size(), 5u);  // the four meshes and the looping file; no "looping" category
    EXPECT_EQ(models[3].file, "box/loop.ply");  // ball/egg, ball/sphere, box/cube, box/loop, ...

    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, fast_options());
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.models_failed, 1u);
    ASSERT_EQ(r.failures.size(), 1u);
    EXPECT_EQ(r.failures[0].model, "box/loop");
    EXPECT_CONTAINS(r.failures[0].error, "loop.ply: cannot read: ");
    EXPECT_CONTAINS(r.failures[0].error, "symbolic links");
    EXPECT_EQ(db.model_status("box", "loop"), ModelStatus::kFailed);
}

TEST_F(TrainingRunTest, ASecondWriterIsRefusedAndNothingMixes) {
    const TrainingOptions o = fast_options();
    Database first(path("db.sqlite"), OpenMode::kWrite);
    // Another training on the same new database, while the first holds it: refused at open.
    EXPECT_EQ(error_of<IoError>([&] { Database second(path("db.sqlite"), OpenMode::kWrite); }),
              path("db.sqlite") + ": database is in use by another training");
    train(root(), first, o);
    {
        const Database reader(path("db.sqlite"));  // readers are never refused
        EXPECT_EQ(reader.summary().models, 4u);
    }
    EXPECT_THROW(Database(path("db.sqlite"), OpenMode::kWrite), IoError);
    first = Database(path("other.sqlite"), OpenMode::kWrite);  // the lock goes with the writer
    Database again(path("db.sqlite"), OpenMode::kWrite);
    EXPECT_EQ(train(root(), again, o).models_existing, 4u);
}

TEST_F(TrainingRunTest, ViewsWithTooFewPointsAreSkippedAndCounted) {
    TrainingOptions o = fast_options();
    o.min_points = 1'000'000;  // no view has that many: every one is skipped
    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.views, 0u);
    EXPECT_EQ(r.views_skipped, 80u);
    const auto views = db.views("box", "cube");
    ASSERT_EQ(views.size(), 20u);
    EXPECT_TRUE(views[0].skipped());
    EXPECT_GT(views[0].points, 0u);
    EXPECT_EQ(views[0].skip_reason,
              "too few points (" + std::to_string(views[0].points) + " < 1000000)");
    EXPECT_EQ(db.summary().skipped_views, 80u);
    EXPECT_EQ(db.load_descriptors().rows(), 0u);
}

TEST_F(TrainingRunTest, CatalogRescalesNonMetricModelsAndSetsGroups) {
    // The cube is "non-metric" with a 0.1 extent: scaled to the box category's metric median,
    // which is the slab's 0.2. The sphere keeps its size and gets a shared group.
    touch("root/catalog.csv",
          "file,category,source,model,group,extent,metric\n"
          "box/cube.ply,box,kit,cube,boxes,0.1,no\n"
          "box/slab.ply,box,ycb,slab,slab,0.2,yes\n"
          "ball/sphere.ply,ball,ycb,sphere,round,0.1,yes\n");
    Database db(path("db.sqlite"), OpenMode::kWrite);
    train(root(), db, fast_options());
    EXPECT_EQ(db.settings().at("rescale_non_metric"), SettingValue(std::string("category_extent")));
    const auto models = db.models();  // ball/egg, ball/sphere, box/cube, box/slab
    ASSERT_EQ(models.size(), 4u);
    EXPECT_EQ(models[0].group, "egg");  // not in the catalog: metric, own group
    EXPECT_EQ(models[0].scale, 1.0);
    EXPECT_EQ(models[1].group, "round");
    EXPECT_EQ(models[1].scale, 1.0);
    EXPECT_EQ(models[2].group, "boxes");
    EXPECT_DOUBLE_EQ(models[2].scale, 2.0);
    EXPECT_EQ(models[3].scale, 1.0);

    // Without the catalog the same database is refused (the scales would differ).
    TrainingOptions o = fast_options();
    o.use_catalog = false;
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(root(), db, o); }),
                    "rescale_non_metric none (database: category_extent)");
}

TEST_F(TrainingRunTest, DatabasesFromBeforeTheCameraSettingsResume) {
    // A database written before the camera band and range existed has no such settings; it was
    // trained from the whole sphere at one distance, so those options resume it.
    const TrainingOptions o = fast_options();
    Database db(path("db.sqlite"), OpenMode::kWrite);
    train(root(), db, o);
    Settings old = db.settings();
    for (const char* key : {"camera_max_distance", "camera_min_elevation", "camera_max_elevation"})
        ASSERT_EQ(old.erase(key), 1u) << key;
    db.set_settings(old);
    const TrainingResult again = train(root(), db, o);
    EXPECT_EQ(again.models_existing, again.models_total);
    // The new defaults are refused, naming what differs and what to do.
    TrainingOptions upper = o;
    upper.render.min_elevation = 0.0;
    const std::string message = error_of<std::invalid_argument>([&] { train(root(), db, upper); });
    EXPECT_CONTAINS(message, "camera_min_elevation 0 (database: unset)");
    EXPECT_CONTAINS(message, "train with the same options to resume, or into a new database");
}

TEST_F(TrainingRunTest, KilledProcessResumesToTheSameDatabase) {
    Database full(path("full.sqlite"), OpenMode::kWrite);
    train(root(), full, fast_options());

    const std::string db_path = path("killed.sqlite"), marker = path("marker");
    const std::string spec = "ESF_TRAINING_TEST_CHILD=" + root() + " " + db_path + " " + marker;
    std::string self = fs::read_symlink("/proc/self/exe").string();
    char* argv[] = {self.data(), nullptr};
    char* envp[] = {const_cast<char*>(spec.c_str()), nullptr};
    pid_t child = 0;
    ASSERT_EQ(posix_spawn(&child, self.c_str(), nullptr, nullptr, argv, envp), 0);
    for (int i = 0; i < 6000 && !fs::exists(marker); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    kill(child, SIGKILL);  // somewhere in models 2 to 4 (or just after, on a fast machine)
    int status = 0;
    waitpid(child, &status, 0);
    ASSERT_TRUE(fs::exists(marker)) << "the training process never committed a model";
    EXPECT_TRUE(WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) == 0));

    {
        const Database killed(db_path);  // readable as it is, log and all
        for (const auto& m : killed.models()) EXPECT_EQ(m.views + m.skipped_views, 20u);
    }
    // The writer's lock goes with the killed process. A mesh importer it was starting at that
    // moment shares the lock's file until its exec (posix_spawn's child closes the descriptor
    // there), so the lock may outlive the process by that instant: allow it a few seconds.
    std::optional<Database> reopened;
    for (int i = 0; i < 500 && !reopened; ++i) {
        try {
            reopened.emplace(db_path, OpenMode::kWrite);
        } catch (const IoError& e) {
            ASSERT_NE(std::string(e.what()).find("in use by another training"), std::string::npos)
                << e.what();
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
    }
    ASSERT_TRUE(reopened.has_value()) << "the killed training's lock never went";
    Database& db = *reopened;
    const TrainingResult r = train(root(), db, fast_options());
    EXPECT_GE(r.models_existing, 1u);
    expect_same(snapshot(full), snapshot(db));
}

TEST_F(TrainingRunTest, ViewsAreTakenFromTheCameraDistanceOrFarEnoughToSeeTheModel) {
    EXPECT_EQ(TrainingOptions{}.render.distance, kTrainingCameraDistance);  // the default
    TrainingOptions o = fast_options();
    o.render.distance = 0.12;  // metres from each model's centre
    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, o);
    ASSERT_EQ(r.models_failed, 0u);
    const auto camera_distance = [&](const std::string& category, const std::string& name) {
        const auto views = db.views(category, name);
        EXPECT_EQ(views.size(), 20u);
        // Every model is centred on its origin, which each camera looks at from its distance.
        return views.at(7).pose.block<3, 1>(0, 3).norm();
    };
    // The sphere (radius 0.05) fits: seen from 0.12 m. The cube's bounding sphere (radius
    // 0.05 sqrt 3 = 0.0866) would not fit: seen from 1.5 times that radius, 0.1299 m.
    EXPECT_NEAR(camera_distance("ball", "sphere"), 0.12, 1e-5);
    EXPECT_NEAR(camera_distance("box", "cube"), 1.5 * 0.05 * std::sqrt(3.0), 1e-4);
}

}  // namespace
}  // namespace esf
