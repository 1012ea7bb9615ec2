// Runs the built `esf` binary (ESF_CLI): a small database from `esf generate` + `esf train
// --level 0`, a test set of views rendered from other generated models (`esf render`), then
// `esf eval` (table, --json, --report, --synthetic, --groups), `esf learn-weights` and the error
// paths: exit codes, stdout, stderr.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_run.hpp"
#include "support/test_data.hpp"

namespace fs = std::filesystem;
using esf::test::CliRun;
using esf::test::quoted;
using esf::test::read_text;

namespace {

std::size_t lines(const std::string& s) {
    std::size_t n = 0;
    for (const char c : s) n += c == '\n';
    return n;
}

const std::vector<std::string> kClasses = {"bottle", "bowl", "mug"};

class CliEvalTest : public ::testing::Test {
  protected:
    static fs::path dir() {
        return fs::temp_directory_path() / ("esf_cli_eval_" + std::to_string(::getpid()));
    }

    static CliRun esf(const std::string& args) { return esf::test::run_esf(args, dir()); }

    // One database and test set for all tests: 2 generated models per class, 20 views each;
    // queries are views of a model generated with another seed.
    static void SetUpTestSuite() {
        fs::remove_all(dir());
        fs::create_directories(dir());
        const std::string categories = "--categories bottle,bowl,mug --threads 2";
        setup_error_ = "generate";
        if (esf("generate -o " + quoted(dir() / "train") + " --per-class 2 --seed 3 " + categories)
                .code != 0)
            return;
        if (esf("generate -o " + quoted(dir() / "test") + " --per-class 1 --seed 77 " + categories)
                .code != 0)
            return;
        setup_error_ = "train";
        const CliRun train = esf("train " + quoted(dir() / "train") + " -o " + quoted(db()) +
                                 " --descriptor esf --min-elevation -90 --level 0 --samples 2000 "
                                 "--threads 2");
        if (train.code != 0) {
            setup_error_ += ": " + train.err;
            return;
        }
        std::ofstream csv(dir() / "set.csv");
        csv << "file,class,note\n";
        for (const std::string& c : kClasses) {
            setup_error_ = "render " + c;
            const fs::path views = dir() / "views" / c;
            if (esf("render " + quoted(dir() / "test" / c / ("gen_" + c + "_000.ply")) + " -o " +
                    quoted(views) + " --level 0 --threads 2")
                    .code != 0)
                return;
            for (const char* view : {"000", "007", "013"})
                csv << "views/" << c << "/view_" << view << ".pcd," << c << ",\"rendered, " << view
                    << "\"\n";
        }
        csv << "views/mug/view_001.pcd,chair,not in the database\n";
        setup_error_.clear();
    }
    static void TearDownTestSuite() { fs::remove_all(dir()); }

    void SetUp() override { ASSERT_TRUE(setup_error_.empty()) << "setup: " << setup_error_; }

    static fs::path db() { return dir() / "db.sqlite"; }
    static fs::path set() { return dir() / "set.csv"; }

    static inline std::string setup_error_;
};

TEST_F(CliEvalTest, JsonHasTheOverallAndPerClassNumbers) {
    const CliRun run = esf("eval --json --threads 2 " + quoted(db()) + " " + quoted(set()));
    ASSERT_EQ(run.code, 0) << run.err;
    const nlohmann::json j = nlohmann::json::parse(run.out);
    const nlohmann::json& overall = j["overall"];
    for (const char* key : {"samples", "top1", "top10", "class_top1", "class_top10"})
        EXPECT_TRUE(overall.contains(key)) << key;
    EXPECT_EQ(overall["samples"], 9);
    for (const char* key : {"top1", "top10", "class_top1", "class_top10"}) {
        EXPECT_GE(overall[key].get<double>(), 0.0) << key;
        EXPECT_LE(overall[key].get<double>(), 1.0) << key;
    }
    EXPECT_GE(overall["top10"].get<double>(), overall["top1"].get<double>());
    EXPECT_EQ(j["skipped"], 1);
    EXPECT_EQ(j["missing_classes"][0]["class"], "chair");
    ASSERT_EQ(j["classes"].size(), 3u);
    for (std::size_t c = 0; c < 3; ++c) {
        const nlohmann::json& row = j["classes"][c];
        EXPECT_EQ(row["class"], kClasses[c]);
        EXPECT_EQ(row["samples"], 3);
        for (const char* key : {"top1", "top10", "confused_with"})
            EXPECT_TRUE(row.contains(key)) << key;
    }
    EXPECT_FALSE(j.contains("queries"));
    EXPECT_GT(j["timings"]["describe_ms"].get<double>(), 0.0);
    EXPECT_EQ(j["weighted"], false);
}

TEST_F(CliEvalTest, TableAndReport) {
    const fs::path report = dir() / "report";
    const CliRun run =
        esf("eval -k 3 --report " + quoted(report) + " " + quoted(db()) + " " + quoted(set()));
    ASSERT_EQ(run.code, 0) << run.err;
    EXPECT_TRUE(run.err.empty()) << run.err;
    for (const char* text : {"per sample", "per class", "3-NN", "most confused with", "mug",
                             "chair 1", "ms per cloud"})
        EXPECT_NE(run.out.find(text), std::string::npos) << text << "\n" << run.out;
    for (const char* file :
         {"report.json", "confusion.png", "confusion.svg", "rank_curves.svg", "index.html"})
        EXPECT_TRUE(fs::is_regular_file(report / file)) << file;
    const nlohmann::json j = nlohmann::json::parse(read_text(report / "report.json"));
    EXPECT_EQ(j["k"], 3);
    EXPECT_EQ(j["queries"].size(), 9u);
}

TEST_F(CliEvalTest, SyntheticLeaveOneModelOutAndGroups) {
    const CliRun run = esf("eval --synthetic --json -k 5 " + quoted(db()));
    ASSERT_EQ(run.code, 0) << run.err;
    const nlohmann::json j = nlohmann::json::parse(run.out);
    EXPECT_EQ(j["overall"]["samples"], 6 * 20);
    EXPECT_EQ(j["test_set"], "leave-one-model-out");
    EXPECT_GT(j["overall"]["top10"].get<double>(), 0.5);

    // Both models of each class in one group: nothing of the query's class is left to find.
    const fs::path catalog = dir() / "catalog.csv";
    {
        std::ofstream out(catalog);
        out << "file,category,group\n";
        for (const std::string& c : kClasses)
            for (const char* i : {"000", "001"})
                out << c << "/gen_" << c << "_" << i << ".ply," << c << "," << c << "\n";
    }
    const CliRun grouped =
        esf("eval --synthetic --json --groups " + quoted(catalog) + " " + quoted(db()));
    ASSERT_EQ(grouped.code, 0) << grouped.err;
    const nlohmann::json g = nlohmann::json::parse(grouped.out);
    EXPECT_EQ(g["test_set"], "leave-one-group-out");
    EXPECT_EQ(g["overall"]["top10"], 0.0);

    // The database's own views as held-out queries: the same as leave-one-model-out.
    const CliRun held =
        esf("eval --synthetic --json -k 5 --queries " + quoted(db()) + " " + quoted(db()));
    ASSERT_EQ(held.code, 0) << held.err;
    const nlohmann::json h = nlohmann::json::parse(held.out);
    EXPECT_EQ(h["overall"]["samples"], 6 * 20);
    EXPECT_EQ(h["overall"]["top1"], j["overall"]["top1"]);
    EXPECT_EQ(h["overall"]["top10"], j["overall"]["top10"]);
    const CliRun wrong =
        esf("eval --queries " + quoted(db()) + " " + quoted(db()) + " " + quoted(set()));
    EXPECT_EQ(wrong.code, 1);
    EXPECT_NE(wrong.err.find("--queries needs --synthetic"), std::string::npos) << wrong.err;
}

TEST_F(CliEvalTest, LearnWeightsStoresWeightsThatEvalUses) {
    const fs::path copy = dir() / "weights.sqlite";
    fs::copy_file(db(), copy, fs::copy_options::overwrite_existing);
    const CliRun run = esf("learn-weights --json --threads 2 --max-queries 60 " + quoted(copy));
    ASSERT_EQ(run.code, 0) << run.err;
    const nlohmann::json j = nlohmann::json::parse(run.out);
    ASSERT_EQ(j["weights"].size(), 10u);
    EXPECT_GE(j["objective_after"].get<double>(), j["objective_before"].get<double>());
    EXPECT_EQ(j["queries"], 60);
    EXPECT_EQ(j["stored"], true);
    EXPECT_TRUE(j["synthetic_after"].contains("top1"));
    EXPECT_TRUE(j["block_weights"].contains("d2_ratio"));

    const CliRun info = esf("info --json " + quoted(copy));
    ASSERT_EQ(info.code, 0) << info.err;
    EXPECT_EQ(nlohmann::json::parse(info.out)["descriptors"][0]["weights"].size(), 10u);
    const CliRun weighted = esf("eval --json " + quoted(copy) + " " + quoted(set()));
    ASSERT_EQ(weighted.code, 0) << weighted.err;
    EXPECT_EQ(nlohmann::json::parse(weighted.out)["weighted"], true);
    const CliRun plain = esf("eval --json --no-weights " + quoted(copy) + " " + quoted(set()));
    EXPECT_EQ(nlohmann::json::parse(plain.out)["weighted"], false);

    const CliRun text = esf("learn-weights --dry-run --iterations 1 " + quoted(copy));
    ASSERT_EQ(text.code, 0) << text.err;
    for (const char* s : {"d2_in", "objective", "synthetic 1-NN", "not stored"})
        EXPECT_NE(text.out.find(s), std::string::npos) << s << "\n" << text.out;
}

TEST_F(CliEvalTest, BadInputIsOneLineAndAnExitCode) {
    // Usage errors: 1.
    EXPECT_EQ(esf("eval " + quoted(db())).code, 1);
    EXPECT_EQ(esf("eval --synthetic " + quoted(db()) + " " + quoted(set())).code, 1);
    EXPECT_EQ(esf("eval " + quoted(dir() / "missing.sqlite") + " " + quoted(set())).code, 1);
    EXPECT_EQ(esf("eval --groups " + quoted(set()) + " " + quoted(db()) + " " + quoted(set())).code,
              1);
    EXPECT_EQ(esf("learn-weights").code, 1);

    // A malformed test set: 2, one line naming the file and line.
    const fs::path bad = dir() / "bad.csv";
    std::ofstream(bad) << "file,label\nx.pcd,mug\n";
    CliRun run = esf("eval " + quoted(db()) + " " + quoted(bad));
    EXPECT_EQ(run.code, 2);
    EXPECT_EQ(lines(run.err), 1u) << run.err;
    EXPECT_EQ(run.err, "esf: error: " + bad.string() + ":1: the header has no 'class' column\n");

    // Nothing evaluable (a missing cloud, an unknown class): warnings, then 2.
    const fs::path none = dir() / "none.csv";
    std::ofstream(none) << "file,class\nmissing.pcd,mug\nviews/mug/view_000.pcd,chair\n";
    run = esf("eval --json " + quoted(db()) + " " + quoted(none));
    EXPECT_EQ(run.code, 2);
    EXPECT_NE(run.err.find("esf: warning: " + (dir() / "missing.pcd").string()), std::string::npos)
        << run.err;
    EXPECT_NE(run.err.find("esf: error: no sample could be evaluated (1 skipped, 1 failed)"),
              std::string::npos)
        << run.err;
    EXPECT_EQ(nlohmann::json::parse(run.out)["failed"], 1);  // still one JSON object

    // A corrupt database: 2, one line starting with its name.
    const fs::path corrupt = dir() / "corrupt.sqlite";
    std::ofstream(corrupt, std::ios::binary) << std::string(2048, 'x');
    for (const std::string& args :
         {"eval " + quoted(corrupt) + " " + quoted(set()), "eval --synthetic " + quoted(corrupt),
          "learn-weights " + quoted(corrupt)}) {
        run = esf(args);
        EXPECT_EQ(run.code, 2) << args;
        EXPECT_EQ(lines(run.err), 1u) << run.err;
        EXPECT_EQ(run.err.rfind("esf: error: " + corrupt.string(), 0), 0u) << run.err;
    }
}

// `esf eval DB --scenes`: two labelled real scenes (a box standing on a box, a box seen on both
// sides of an occluder) through segmentation and recognition; the database's classes are not
// the scenes', so only the segmentation figures are checked.
TEST_F(CliEvalTest, ScenesThroughSegmentationAndRecognition) {
    ESF_REQUIRE_DATA("real/scenes/mosd_learn28.pcd");
    const fs::path scenes = dir() / "scenes.csv";
    const std::string stacked = esf::test::data_file("real/scenes/mosd_learn20.pcd").string();
    const std::string occluded = esf::test::data_file("real/scenes/mosd_learn28.pcd").string();
    std::ofstream(scenes) << "scene_file,object_id,class,scene_type\n"
                          << stacked << ",2,box,stacked\n"
                          << stacked << ",3,box,stacked\n"
                          << occluded << ",2,box,occluded\n"
                          << occluded << ",3,box,occluded\n";
    CliRun run = esf("eval " + quoted(db()) + " --scenes " + quoted(scenes) + " --json");
    ASSERT_EQ(run.code, 0) << run.err;
    nlohmann::json j = nlohmann::json::parse(run.out);
    ASSERT_EQ(j["types"].size(), 3u);  // occluded, stacked, all
    const nlohmann::json& all = j["types"][2];
    EXPECT_EQ(all["type"], "all");
    EXPECT_EQ(all["scenes"], 2);
    EXPECT_EQ(all["objects"], 4);
    EXPECT_EQ(all["found"], 4);
    EXPECT_EQ(all["labelled"], 4);
    EXPECT_EQ(j["objects"].size(), 4u);
    EXPECT_EQ(j["objects"][0]["outcome"], "found");
    EXPECT_EQ(j["objects"][0]["class"], "box");
    EXPECT_GT(j["timings"]["segment_ms_per_frame"].get<double>(), 0.0);

    // Euclidean clustering glues the stacked boxes and splits the occluded one.
    run = esf("eval " + quoted(db()) + " --scenes " + quoted(scenes) + " --grouping euclidean " +
              "--json");
    ASSERT_EQ(run.code, 0) << run.err;
    j = nlohmann::json::parse(run.out);
    EXPECT_EQ(j["types"][2]["found"], 1);
    EXPECT_EQ(j["types"][1]["merged"], 2);

    // The segmentation's thresholds as esf scene has them: clusters of a million points or
    // more only, so none is kept and every object is missed.
    run = esf("eval " + quoted(db()) + " --scenes " + quoted(scenes) +
              " --min-cluster-points 1000000 --json");
    ASSERT_EQ(run.code, 0) << run.err;
    j = nlohmann::json::parse(run.out);
    EXPECT_EQ(j["types"][2]["found"], 0);
    EXPECT_EQ(j["types"][2]["missed"], 4);
    // A negative count is a usage error, not a huge unsigned one.
    EXPECT_EQ(
        esf("eval " + quoted(db()) + " --scenes " + quoted(scenes) + " --min-cluster-points -5")
            .code,
        1);

    // --report: scenes.json holds what --json prints; index.html the tables.
    const fs::path report = dir() / "scene_report";
    run = esf("eval " + quoted(db()) + " --scenes " + quoted(scenes) + " --report " +
              quoted(report) + " --json");
    ASSERT_EQ(run.code, 0) << run.err;
    EXPECT_EQ(read_text(report / "scenes.json"), run.out);
    const std::string html = read_text(report / "index.html");
    EXPECT_NE(html.find("<h2>All objects</h2>"), std::string::npos);
    EXPECT_NE(html.find("mosd_learn28.pcd"), std::string::npos);

    // The table.
    run = esf("eval " + quoted(db()) + " --scenes " + quoted(scenes));
    ASSERT_EQ(run.code, 0) << run.err;
    EXPECT_NE(run.out.find("stacked"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("end-to-end"), std::string::npos) << run.out;

    // Usage errors: 1; a bad scene set: 2, one line naming the file and line.
    EXPECT_EQ(
        esf("eval " + quoted(db()) + " " + quoted(set()) + " --scenes " + quoted(scenes)).code, 1);
    const fs::path bad = dir() / "bad_scenes.csv";
    std::ofstream(bad) << "scene_file,object_id,class\nx.pcd,two,box\n";
    run = esf("eval " + quoted(db()) + " --scenes " + quoted(bad));
    EXPECT_EQ(run.code, 2);
    EXPECT_EQ(run.err, "esf: error: " + bad.string() +
                           ":2: object_id is not a non-negative integer: 'two'\n");
}

TEST_F(CliEvalTest, HelpDescribesEveryOption) {
    for (const char* command : {"eval", "learn-weights"}) {
        const CliRun run = esf(std::string(command) + " --help");
        EXPECT_EQ(run.code, 0);
        for (const char* option : {"--threads", "--groups", "--json"})
            EXPECT_NE(run.out.find(option), std::string::npos) << command << " " << option;
    }
    const CliRun all = esf("--help");
    EXPECT_NE(all.out.find("eval"), std::string::npos);
    EXPECT_NE(all.out.find("learn-weights"), std::string::npos);
}

}  // namespace
