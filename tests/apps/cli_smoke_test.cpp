// Runs the built `esf` binary (ESF_CLI) on small generated inputs: help, describe, classify and
// scene, and the error paths (missing file, corrupt database): exit codes, stdout, stderr.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/training/database.hpp"
#include "support/cli_run.hpp"
#include "support/one_view_database.hpp"

namespace fs = std::filesystem;
using esf::test::CliRun;
using esf::test::quoted;
using esf::test::read_text;

namespace {

class CliSmokeTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("esf_cli_smoke_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    CliRun esf(const std::string& args) const { return esf::test::run_esf(args, dir_); }

    /// A closed box surface, 6 cm x 4 cm x 10 cm, 1 mm grid, as x y z text.
    std::string write_box(const std::string& name) const {
        esf::PointCloud cloud;
        std::mt19937_64 rng(1);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        const Eigen::Vector3f size(0.06f, 0.04f, 0.10f);
        for (int i = 0; i < 3000; ++i) {
            Eigen::Vector3f p(u(rng), u(rng), u(rng));
            const int face = i % 6;
            p[face / 2] = float(face % 2);
            cloud.points.push_back(p.cwiseProduct(size) + Eigen::Vector3f(0, 0, 1));
        }
        cloud.width = static_cast<std::uint32_t>(cloud.points.size());
        const std::string path = (dir_ / name).string();
        esf::write_pcd(path, cloud);
        return path;
    }

    /// A cube of 10 cm as an OBJ mesh.
    std::string write_cube(const std::string& name) const {
        const std::string path = (dir_ / name).string();
        std::ofstream out(path);
        for (int i = 0; i < 8; ++i)
            out << "v " << 0.1 * (i & 1) << ' ' << 0.1 * ((i >> 1) & 1) << ' '
                << 0.1 * ((i >> 2) & 1) << '\n';
        for (const char* face : {"1 3 4 2", "5 6 8 7", "1 2 6 5", "3 7 8 4", "1 5 7 3", "2 4 8 6"})
            out << "f " << face << '\n';
        return path;
    }

    /// What the dynamic loader logged (LD_DEBUG=files) while `esf ARGS` ran: every shared
    /// library each process of the run opened.
    std::string loader_log(const std::string& args) const {
        const fs::path log = dir_ / "loader";
        ::setenv("LD_DEBUG", "files", 1);
        ::setenv("LD_DEBUG_OUTPUT", log.c_str(), 1);  // one file per process: loader.PID
        const CliRun run = esf(args);
        ::unsetenv("LD_DEBUG");
        ::unsetenv("LD_DEBUG_OUTPUT");
        EXPECT_EQ(run.code, 0) << args << ": " << run.err;
        std::string text;
        for (const auto& entry : fs::directory_iterator(dir_)) {
            if (entry.path().filename().string().rfind("loader.", 0) != 0) continue;
            text += read_text(entry.path());
            fs::remove(entry.path());
        }
        return text;
    }

    fs::path dir_;
};

std::size_t lines(const std::string& s) {
    std::size_t n = 0;
    for (const char c : s) n += c == '\n';
    return n;
}

TEST_F(CliSmokeTest, HelpListsTheCommands) {
    const CliRun run = esf("--help");
    EXPECT_EQ(run.code, 0) << run.err;
    for (const char* command : {"describe", "train", "segment", "classify", "scene"})
        EXPECT_NE(run.out.find(command), std::string::npos) << command;
    const CliRun classify = esf("classify --help");
    EXPECT_EQ(classify.code, 0);
    EXPECT_NE(classify.out.find("row-major"), std::string::npos);
}

TEST_F(CliSmokeTest, DescribeWritesOneCsvLinePerFile) {
    const std::string box = write_box("box.pcd");
    const CliRun run = esf("describe --samples 2000 " + quoted(box));
    ASSERT_EQ(run.code, 0) << run.err;
    EXPECT_EQ(lines(run.out), 1u);
    EXPECT_EQ(run.out.rfind(box + ",", 0), 0u);
    std::size_t commas = 0;
    for (const char c : run.out) commas += c == ',';
    EXPECT_EQ(commas, static_cast<std::size_t>(esf::kEsfSize));
}

TEST_F(CliSmokeTest, OnlyRenderingOpensEmbree) {
    if (ESF_EMBREE_AT_START)
        GTEST_SKIP() << "built with ESF_EMBREE_AT_START: Embree loads with the program";
    const std::string box = write_box("box.pcd");
    const std::string describing = loader_log("describe --samples 2000 " + quoted(box));
    ASSERT_NE(describing.find("libstdc++"), std::string::npos) << "no log of esf's own loading";
    EXPECT_EQ(describing.find("libembree3"), std::string::npos) << describing;
    const std::string rendering =
        loader_log("render --level 0 --width 64 --height 48 -o " + quoted(dir_ / "views") + " " +
                   quoted(write_cube("cube.obj")));
    EXPECT_NE(rendering.find("libembree3"), std::string::npos);
}

TEST_F(CliSmokeTest, DescribeCsvValuesAreTheLibrarysBitForBit) {
    // Shortest round-trip text (std::to_chars): every value reads back as the same float.
    const std::string box = write_box("box.pcd");
    const CliRun run = esf("describe --samples 2000 --threads 1 " + quoted(box));
    ASSERT_EQ(run.code, 0) << run.err;
    esf::EsfOptions options;
    options.samples = 2000;
    const esf::EsfResult expected = esf::compute_esf(esf::read_cloud(box).points, options);
    std::vector<float> values;
    std::size_t pos = run.out.find(',');
    while (pos != std::string::npos) {
        const std::size_t end = run.out.find_first_of(",\n", pos + 1);
        values.push_back(std::stof(run.out.substr(pos + 1, end - pos - 1)));
        pos = run.out[end] == ',' ? end : std::string::npos;
    }
    ASSERT_EQ(values.size(), expected.descriptor.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
        ASSERT_EQ(values[i], expected.descriptor[i]) << "bin " << i;
    }
}

TEST_F(CliSmokeTest, DescribeJsonCountsTheDroppedPointsOfAnOrganisedScan) {
    // An organised scan with missing depths (NaN rows and scattered gaps), compressed as PCL
    // stores scenes: the points, dropped points and descriptor of the library on the whole cloud.
    esf::PointCloud scan = esf::read_cloud(write_box("box.pcd"));
    for (std::size_t i = 0; i < scan.points.size(); ++i)
        if (i % 7 == 3 || (i / 100) % 5 == 2)
            scan.points[i][static_cast<int>(i % 3)] = std::numeric_limits<float>::quiet_NaN();
    scan.width = 100;
    scan.height = static_cast<std::uint32_t>(scan.points.size() / 100);
    const std::string path = (dir_ / "scan.pcd").string();
    esf::write_pcd(path, scan, esf::PcdEncoding::kBinaryCompressed);
    const CliRun run = esf("describe --samples 2000 --threads 1 --format json " + quoted(path));
    ASSERT_EQ(run.code, 0) << run.err;
    const nlohmann::json out = nlohmann::json::parse(run.out);
    esf::EsfOptions options;
    options.samples = 2000;
    const esf::EsfResult expected = esf::compute_esf(scan.points, options);
    ASSERT_GT(expected.dropped_points, 0u);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0]["points"].get<std::size_t>(), expected.points);
    EXPECT_EQ(out[0]["dropped_points"].get<std::size_t>(), expected.dropped_points);
    EXPECT_EQ(out[0]["descriptor"].get<std::vector<float>>(),
              std::vector<float>(expected.descriptor.begin(), expected.descriptor.end()));

    // Too few finite points: the estimator's message, dropped points included.
    scan.points.resize(300);
    scan.width = 300;
    scan.height = 1;
    for (std::size_t i = 1; i < scan.points.size(); ++i) scan.points[i].x() = -INFINITY;
    esf::write_pcd(path, scan, esf::PcdEncoding::kBinaryCompressed);
    const CliRun few = esf("describe " + quoted(path));
    EXPECT_EQ(few.code, 2);
    EXPECT_EQ(few.err,
              "esf: error: " + path +
                  ": ESF needs at least 3 finite points, got 1 (299 non-finite dropped)\n");
}

TEST_F(CliSmokeTest, DescribeGoesOnPastAMissingFile) {
    const std::string box = write_box("box.pcd");
    const std::string missing = (dir_ / "missing.pcd").string();
    const CliRun run = esf("describe --samples 2000 " + quoted(box) + " " + quoted(missing));
    EXPECT_EQ(run.code, 2);
    EXPECT_EQ(lines(run.out), 1u);  // the good file is still described
    EXPECT_EQ(lines(run.err), 1u) << run.err;
    EXPECT_NE(run.err.find("esf: error: " + missing), std::string::npos) << run.err;
}

TEST_F(CliSmokeTest, ClassifyWithACorruptDatabaseIsOneLine) {
    const std::string box = write_box("box.pcd");
    const std::string db = (dir_ / "corrupt.sqlite").string();
    {
        std::ofstream out(db, std::ios::binary);
        out << std::string(2048, 'x');
    }
    const CliRun run = esf("classify " + quoted(db) + " " + quoted(box));
    EXPECT_EQ(run.code, 2);
    EXPECT_TRUE(run.out.empty()) << run.out;
    EXPECT_EQ(lines(run.err), 1u) << run.err;
    EXPECT_EQ(run.err.rfind("esf: error: " + db, 0), 0u) << run.err;
}

TEST_F(CliSmokeTest, ClassifyPrintsJsonAndReportsBadFiles) {
    // A database of two "models" whose single views are the descriptors of the box and of a
    // flat plate, described with the settings the command will use.
    const std::string box = write_box("box.pcd");
    esf::Points plate;
    for (int i = 0; i < 60; ++i)
        for (int j = 0; j < 60; ++j) plate.push_back({0.002f * float(i), 0.002f * float(j), 1.0f});
    const std::string db_path = (dir_ / "db.sqlite").string();
    esf::test::write_one_view_database(db_path,
                                       {{"box", esf::read_cloud(box).points}, {"plate", plate}});
    const std::string missing = (dir_ / "missing.pcd").string();
    const CliRun run =
        esf("classify --json -k 2 " + quoted(db_path) + " " + quoted(box) + " " + quoted(missing));
    EXPECT_EQ(run.code, 2);
    // The missing file, and a warning: this database stores no model surfaces, so the default
    // verification cannot run.
    EXPECT_EQ(lines(run.err), 2u) << run.err;
    EXPECT_NE(run.err.find(missing), std::string::npos);
    EXPECT_NE(run.err.find("esf: warning: " + db_path +
                           ": verification off: 2 of 2 models have no stored surface"),
              std::string::npos)
        << run.err;
    const nlohmann::json out = nlohmann::json::parse(run.out);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0]["file"], box);
    EXPECT_EQ(out[0]["class"], "box");
    EXPECT_EQ(out[0]["model"], "box_1");
    EXPECT_EQ(out[0]["distance"], 0.0);  // the same cloud, the same settings
    EXPECT_EQ(out[0]["confidence"], 0.5);
    ASSERT_EQ(out[0]["neighbours"].size(), 2u);
    EXPECT_EQ(out[0]["neighbours"][1]["class"], "plate");
    EXPECT_EQ(out[0]["neighbours"][0]["pose"].size(), 16u);

    const CliRun table = esf("classify --no-verify " + quoted(db_path) + " " + quoted(box));
    EXPECT_EQ(table.code, 0) << table.err;
    EXPECT_EQ(table.err, "");         // k-NN only, as asked: no warning
    EXPECT_EQ(lines(table.out), 2u);  // header + one row
    EXPECT_NE(table.out.find("box_1"), std::string::npos);
}

}  // namespace
