// Training without rendering: finding models, catalogs, seeds, the settings a database
// records, and the options refused before anything is trained.

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "esf/core/error.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/training/training.hpp"
#include "support/error_of.hpp"
#include "support/training_fixture.hpp"

namespace esf::test {
namespace {

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

}  // namespace
}  // namespace esf::test
