// Runs the built `esf` binary (ESF_CLI): `esf demo` (help, a small run as JSON and as text, a
// report folder, usage errors) and `esf generate`.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/cli_run.hpp"

namespace fs = std::filesystem;
using esf::test::CliRun;
using esf::test::quoted;
using esf::test::read_text;

namespace {

// A small demo: 1 training model per category from 20 views, 1 held-out model x 3 views, a
// scene of 4 objects.
const std::string kSmall =
    "--per-class 1 --level 0 --query-models 1 --query-views 3 --scene-objects 4 --threads 2";

class CliDemoTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("esf_cli_demo_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    CliRun esf(const std::string& args) const { return esf::test::run_esf(args, dir_); }

    fs::path dir_;
};

TEST_F(CliDemoTest, HelpListsTheOptions) {
    const CliRun run = esf("demo --help");
    ASSERT_EQ(run.code, 0) << run.err;
    for (const char* option : {"--seed", "--per-class", "--report", "--work", "--json", "--threads",
                               "--level", "--query-models", "--query-views", "--scene-objects"})
        EXPECT_NE(run.out.find(option), std::string::npos) << option;
    EXPECT_NE(run.out.find("held-out"), std::string::npos);
}

TEST_F(CliDemoTest, SmallRunAsJson) {
    const CliRun run = esf("demo --seed 3 --json " + kSmall);
    ASSERT_EQ(run.code, 0) << run.err;
    const nlohmann::json j = nlohmann::json::parse(run.out);
    for (const char* key : {"seed", "categories", "work_dir", "database", "training", "queries",
                            "table", "confusion", "scene", "seconds"})
        EXPECT_TRUE(j.contains(key)) << key;
    EXPECT_EQ(j["seed"], 3);
    EXPECT_EQ(j["categories"].size(), 10u);
    EXPECT_EQ(j["work_dir_removed"], true);
    EXPECT_FALSE(fs::exists(j["work_dir"].get<std::string>()));
    EXPECT_EQ(j["training"]["models"], 10);
    EXPECT_EQ(j["training"]["views_per_model"], 20);
    EXPECT_EQ(j["queries"]["views"], 30);
    ASSERT_EQ(j["table"].size(), 10u);
    for (const nlohmann::json& row : j["table"]) {
        for (const char* key : {"class", "views", "top1", "top10", "confused_with"})
            EXPECT_TRUE(row.contains(key)) << key;
        EXPECT_GE(row["top10"].get<double>(), row["top1"].get<double>());
    }
    const double top1 = j["queries"]["top1"].get<double>();
    EXPECT_GE(top1, 0.0);
    EXPECT_LE(top1, 1.0);
    const nlohmann::json& scene = j["scene"];
    EXPECT_EQ(scene["placed"].size(), 4u);
    EXPECT_TRUE(scene["plane_found"].get<bool>());
    EXPECT_GE(scene["objects"].size(), 1u);
    for (const nlohmann::json& o : scene["objects"])
        for (const char* key : {"class", "confidence", "centroid", "size", "points", "placed",
                                "true_class", "correct"})
            EXPECT_TRUE(o.contains(key)) << key;
    EXPECT_GE(scene["found"].get<int>(), 3);
    // --json prints nothing but the object: the progress bar is only drawn on a terminal.
    EXPECT_EQ(run.err, "");
}

TEST_F(CliDemoTest, SmallRunAsTextWithReportAndWorkFolder) {
    const fs::path report = dir_ / "report", work = dir_ / "work";
    const CliRun run = esf("demo " + kSmall + " --report " + quoted(report.string()) + " --work " +
                           quoted(work.string()));
    ASSERT_EQ(run.code, 0) << run.err;
    for (const char* text : {"[1/4] generating 10 training models", "[2/4] training", "views/s",
                             "[3/4] querying", "Table I", "1-NN", "10-NN", "most confused",
                             "[4/4] scene", "placed objects found", "total"})
        EXPECT_NE(run.out.find(text), std::string::npos) << text << "\n" << run.out;
    for (const char* file : {"index.html", "report.json", "confusion.png", "rank_curves.svg",
                             "demo.json", "scene.html", "scene.pcd", "scene_depth.png"})
        EXPECT_TRUE(fs::exists(report / file)) << file;
    // The scene page: the frame with an outline and a label per recognised object.
    const std::string page = read_text(report / "scene.html");
    EXPECT_NE(page.find("<image width="), std::string::npos);
    EXPECT_NE(page.find("<polygon"), std::string::npos);
    EXPECT_NE(page.find("<tr class=\"object\">"), std::string::npos);
    const nlohmann::json demo = nlohmann::json::parse(read_text(report / "demo.json"));
    EXPECT_EQ(demo["table"].size(), 10u);
    // The work folder keeps the models and the database.
    bool database = false;
    for (const fs::directory_entry& e : fs::directory_iterator(work))
        database = database || e.path().extension() == ".db";
    EXPECT_TRUE(database);
}

TEST_F(CliDemoTest, UsageErrorsExitOne) {
    const CliRun zero = esf("demo --per-class 0");
    EXPECT_EQ(zero.code, 1);
    EXPECT_NE(zero.err.find("--per-class"), std::string::npos) << zero.err;
    const CliRun unknown = esf("demo --no-such-option");
    EXPECT_EQ(unknown.code, 1);
}

TEST_F(CliDemoTest, UnwritableWorkFolderExitsTwo) {
    const fs::path file = dir_ / "a_file";
    std::ofstream(file) << "x";
    const CliRun run = esf("demo " + kSmall + " --work " + quoted((file / "sub").string()));
    EXPECT_EQ(run.code, 2);
    EXPECT_EQ(run.err.rfind("esf: error: ", 0), 0u) << run.err;
    EXPECT_NE(run.err.find("work folder"), std::string::npos) << run.err;
}

TEST_F(CliDemoTest, GenerateWritesTenCategoryFolders) {
    const fs::path out = dir_ / "models";
    const CliRun run = esf("generate -o " + quoted(out.string()) + " --per-class 1");
    ASSERT_EQ(run.code, 0) << run.err;
    std::size_t folders = 0;
    for (const fs::directory_entry& e : fs::directory_iterator(out)) {
        ASSERT_TRUE(e.is_directory()) << e.path();
        ++folders;
        std::size_t plys = 0;
        for (const fs::directory_entry& f : fs::directory_iterator(e.path())) {
            EXPECT_EQ(f.path().extension(), ".ply") << f.path();
            EXPECT_GT(fs::file_size(f.path()), 1000u) << f.path();
            ++plys;
        }
        EXPECT_EQ(plys, 1u) << e.path();
    }
    EXPECT_EQ(folders, 10u);
    EXPECT_TRUE(fs::exists(out / "mug" / "gen_mug_000.ply"));
    EXPECT_NE(run.out.find("10 models"), std::string::npos) << run.out;
}

}  // namespace
