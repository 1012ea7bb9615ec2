// Runs the built `esf` binary (ESF_CLI): `train --descriptor` on a tiny generated root, `info`
// of the database it made, the error paths of descriptor names, and `compare` of two
// descriptors (table and JSON).

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/cli_run.hpp"
#include "support/error_of.hpp"
#include "support/require_baselines.hpp"

namespace fs = std::filesystem;
using esf::test::CliRun;
using esf::test::quoted;
using esf::test::read_text;

namespace {

/// One generated model each of two categories (mug, bowl) and a small test set of their
/// rendered views (other noise seeds than training), in a fresh temp folder per test.
class CliCompareTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("esf_cli_compare_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        const CliRun gen = esf("generate -o " + quoted(path("root")) +
                               " --per-class 1 --categories mug,bowl --seed 3");
        ASSERT_EQ(gen.code, 0) << gen.err;
    }
    void TearDown() override { fs::remove_all(dir_); }

    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    CliRun esf(const std::string& args) const { return esf::test::run_esf(args, dir_); }

    /// Renders views 0, 7 and 13 of the generated mug and bowl (noise seed 11) and writes
    /// test.csv (file,class) listing them, plus one row of a class no database has.
    std::string write_test_set() const {
        std::ofstream csv(dir_ / "test.csv");
        csv << "file,class\n";
        for (const std::string category : {"mug", "bowl"}) {
            const std::string mesh = path("root/" + category + "/gen_" + category + "_000.ply");
            const CliRun run = esf("render " + quoted(mesh) + " -o " + quoted(path(category)) +
                                   " --level 0 --seed 11");
            EXPECT_EQ(run.code, 0) << run.err;
            for (const char* view : {"view_000.pcd", "view_007.pcd", "view_013.pcd"})
                csv << category << "/" << view << "," << category << "\n";
        }
        csv << "mug/view_001.pcd,teapot\n";  // not a class of the database: skipped
        return path("test.csv");
    }

    fs::path dir_;
};

TEST_F(CliCompareTest, TrainWithABaselineDescriptorAndClassifyWithIt) {
    ESF_REQUIRE_BASELINES();
    const std::string db = path("vfh.sqlite");
    const CliRun train = esf("train " + quoted(path("root")) + " -o " + quoted(db) +
                             " --descriptor vfh --level 0 --json");
    ASSERT_EQ(train.code, 0) << train.err;
    const nlohmann::json summary = nlohmann::json::parse(train.out);
    EXPECT_EQ(summary["descriptor"], "vfh");
    EXPECT_EQ(summary["models_trained"], 2);
    // Level 0 has 20 cameras; training keeps the 12 at elevation >= 0 by default.
    EXPECT_EQ(summary["views"].get<int>() + summary["skipped_views"].get<int>(), 2 * 12);

    const CliRun info = esf("info --json " + quoted(db));
    ASSERT_EQ(info.code, 0) << info.err;
    const nlohmann::json out = nlohmann::json::parse(info.out);
    ASSERT_EQ(out["descriptors"].size(), 1u);
    EXPECT_EQ(out["descriptors"][0]["name"], "vfh");
    EXPECT_EQ(out["descriptors"][0]["dimension"], 308);
    EXPECT_EQ(out["settings"]["descriptor"], "vfh");
    EXPECT_EQ(out["settings"]["descriptor_dimension"], 308);
    EXPECT_EQ(out["settings"]["view_sphere_level"], 0);
    EXPECT_EQ(out["models"], 2);

    // A Recognizer on the vfh database describes a query with vfh and classifies it.
    write_test_set();
    const CliRun classify =
        esf("classify --json -k 3 " + quoted(db) + " " + quoted(path("mug/view_007.pcd")) + " " +
            quoted(path("bowl/view_013.pcd")));
    ASSERT_EQ(classify.code, 0) << classify.err;
    const nlohmann::json classes = nlohmann::json::parse(classify.out);
    ASSERT_EQ(classes.size(), 2u);
    EXPECT_EQ(classes[0]["class"], "mug");
    EXPECT_EQ(classes[1]["class"], "bowl");

    // Another descriptor into the same database is refused, naming both.
    const CliRun other = esf("train " + quoted(path("root")) + " -o " + quoted(db) + " --level 0");
    EXPECT_EQ(other.code, 2);
    EXPECT_CONTAINS(other.err, "esf: error: " + db + ": database holds vfh descriptors, not esf");
}

TEST_F(CliCompareTest, ABaselineWithoutItsModuleSaysHowToGetIt) {
    // As in a build without PCL: the module is not where ESF_BASELINES points.
    ASSERT_EQ(setenv("ESF_BASELINES", path("missing/libesf_baselines.so").c_str(), 1), 0);
    const CliRun train = esf("train " + quoted(path("root")) + " -o " + quoted(path("vfh.sqlite")) +
                             " --descriptor vfh --level 0");
    const CliRun esf_train = esf("train " + quoted(path("root")) + " -o " +
                                 quoted(path("esf.sqlite")) + " --descriptor esf --level 0");
    unsetenv("ESF_BASELINES");
    EXPECT_NE(train.code, 0);
    EXPECT_CONTAINS(train.err, "esf: error: vfh is a PCL baseline");
    EXPECT_CONTAINS(train.err, "-DESF_WITH_PCL=ON");
    EXPECT_EQ(std::count(train.err.begin(), train.err.end(), '\n'), 1) << train.err;
    EXPECT_FALSE(fs::exists(path("vfh.sqlite")));
    EXPECT_EQ(esf_train.code, 0) << esf_train.err;  // everything else works
}

TEST_F(CliCompareTest, UnknownDescriptorNamesListTheValidOnes) {
    const CliRun train = esf("train " + quoted(path("root")) + " -o " + quoted(path("db.sqlite")) +
                             " --descriptor fpfh --level 0");
    EXPECT_EQ(train.code, 1);
    EXPECT_CONTAINS(train.err, "fpfh");
    for (const char* name : {"esf", "pcl-esf", "sdvs", "d2", "vfh", "cvfh", "our-cvfh", "gasd"})
        EXPECT_CONTAINS(train.err, name);
    EXPECT_FALSE(fs::exists(path("db.sqlite")));

    const std::string test_set = path("test.csv");
    std::ofstream(test_set) << "file,class\n";
    const CliRun compare = esf("compare " + quoted(path("root")) + " " + quoted(test_set) +
                               " --descriptors esf,fpfh --work " + quoted(path("work")));
    EXPECT_EQ(compare.code, 1);
    EXPECT_CONTAINS(compare.err,
                    "unknown descriptor 'fpfh' (valid: esf, esf-angles, pcl-esf, sdvs, d2, vfh");
    EXPECT_FALSE(fs::exists(path("work")));  // nothing trained
}

TEST_F(CliCompareTest, ABrokenMeshIsNamedAndTheOthersAreStored) {
    std::ofstream(path("root/bowl/broken.ply")) << "ply\ngarbage\n";
    const std::string db = path("db.sqlite");
    const CliRun train = esf("train " + quoted(path("root")) + " -o " + quoted(db) +
                             " --level 0 --samples 2000 --threads 2");
    EXPECT_EQ(train.code, 2) << train.err;
    EXPECT_CONTAINS(train.err, "bowl/broken failed: " + path("root/bowl/broken.ply"));
    EXPECT_CONTAINS(train.out, "trained 2 models");
    EXPECT_CONTAINS(train.out, "1 failed");
    const CliRun info = esf("info --json " + quoted(db));
    ASSERT_EQ(info.code, 0) << info.err;
    EXPECT_EQ(nlohmann::json::parse(info.out).at("models"), 2);
}

TEST_F(CliCompareTest, CompareTwoDescriptorsPrintsOneRowEach) {
    ESF_REQUIRE_BASELINES();
    const std::string test_set = write_test_set();
    const std::string common = "compare " + quoted(path("root")) + " " + quoted(test_set) +
                               " --descriptors esf,vfh --level 0 -k 3 --work " +
                               quoted(path("work"));
    const CliRun table = esf(common);
    ASSERT_EQ(table.code, 0) << table.err;
    EXPECT_CONTAINS(table.out, "real 1-NN");
    EXPECT_CONTAINS(table.out, "real 3-NN");
    EXPECT_CONTAINS(table.out, "\nesf ");
    EXPECT_CONTAINS(table.out, "\nvfh ");
    EXPECT_CONTAINS(table.out, "6 clouds");
    EXPECT_TRUE(fs::exists(path("work/esf.sqlite")));
    EXPECT_TRUE(fs::exists(path("work/vfh.sqlite")));

    // The second run reuses both databases (nothing trained) and prints JSON.
    const CliRun json = esf(common + " --json");
    ASSERT_EQ(json.code, 0) << json.err;
    const nlohmann::json out = nlohmann::json::parse(json.out);
    EXPECT_EQ(out["k"], 3);
    ASSERT_EQ(out["descriptors"].size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        const nlohmann::json& row = out["descriptors"][i];
        SCOPED_TRACE(row.dump());
        EXPECT_EQ(row["descriptor"], i == 0 ? "esf" : "vfh");
        EXPECT_FALSE(row.contains("error"));
        EXPECT_EQ(row["train_seconds"], 0.0);  // complete: reused
        EXPECT_EQ(row["models"], 2);
        EXPECT_EQ(row["real"]["samples"], 6);
        EXPECT_EQ(row["real"]["skipped"], 1);  // the teapot
        EXPECT_EQ(row["synthetic"]["samples"], row["views"]);
        for (const char* key : {"top1", "topk"}) {
            EXPECT_GE(row["real"][key].get<double>(), 0.0);
            EXPECT_LE(row["real"][key].get<double>(), 1.0);
            EXPECT_GE(row["synthetic"][key].get<double>(), row["synthetic"]["top1"].get<double>());
        }
        EXPECT_GE(row["real"]["topk"].get<double>(), row["real"]["top1"].get<double>());
        EXPECT_GT(row["ms_per_descriptor"].get<double>(), 0.0);
        EXPECT_GT(row["ms_per_match"].get<double>(), 0.0);
    }
    // Two views of two models: the rendered views of the trained models are recognised.
    EXPECT_GE(out["descriptors"][0]["real"]["top1"].get<double>(), 0.8);
}

}  // namespace
