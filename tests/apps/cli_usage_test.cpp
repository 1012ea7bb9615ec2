// Runs the built `esf` binary (ESF_CLI): usage errors from the argument parser come out as one
// line "esf: error: ..." on stderr with exit status 1; runtime errors exit 2; --help and
// --version still print to stdout and exit 0; `esf --help` fits on one screen.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_run.hpp"

namespace fs = std::filesystem;
using esf::test::CliRun;
using esf::test::quoted;

namespace {

class CliUsageTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("esf_cli_usage_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    CliRun esf(const std::string& args) const { return esf::test::run_esf(args, dir_); }

    /// Exit 1, nothing on stdout, and exactly one line on stderr: "esf: error: ..." naming
    /// `mentioned`.
    void expect_usage_error(const std::string& args, const std::string& mentioned) const {
        SCOPED_TRACE("esf " + args);
        const CliRun run = esf(args);
        EXPECT_EQ(run.code, 1);
        EXPECT_EQ(run.out, "");
        EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
        EXPECT_EQ(run.err.rfind("esf: error: ", 0), 0u) << run.err;
        EXPECT_NE(run.err.find(mentioned), std::string::npos) << run.err;
        EXPECT_EQ(run.err.find("--help for more"), std::string::npos) << run.err;
    }

    fs::path dir_;
};

TEST_F(CliUsageTest, ParserErrorsAreOneLineAndExitOne) {
    // The files exist, so that only -k is wrong.
    const std::string db = (dir_ / "db.sqlite").string(), cloud = (dir_ / "x.pcd").string();
    std::ofstream(db) << "";
    std::ofstream(cloud) << "";
    expect_usage_error("classify " + quoted(db) + " " + quoted(cloud) + " -k 0", "-k");
    expect_usage_error("frobnicate", "unknown command 'frobnicate'");
    expect_usage_error("frobnicate --threads 2", "unknown command 'frobnicate'");
    expect_usage_error("", "subcommand");
    expect_usage_error("describe", "files");
    expect_usage_error("describe x.pcd --threads -1", "--threads");
    expect_usage_error("describe x.pcd --format xml", "xml");
    expect_usage_error("describe x.pcd --no-such-option", "--no-such-option");
    // Training views are drawn from the meshes only on report pages.
    expect_usage_error(
        "scene " + quoted(db) + " " + quoted(cloud) + " --meshes " + quoted(dir_.string()),
        "--meshes needs --report DIR");
    expect_usage_error(
        "eval --synthetic " + quoted(db) + " --report r --meshes " + quoted(dir_.string()),
        "--meshes needs a TESTSET.csv and --report DIR");
    expect_usage_error("eval " + quoted(db) + " " + quoted(cloud) + " --gallery -2", "--gallery");
}

TEST_F(CliUsageTest, RuntimeErrorsExitTwo) {
    const std::string missing = (dir_ / "missing.pcd").string();
    const CliRun run = esf("describe --threads 1 " + quoted(missing));
    EXPECT_EQ(run.code, 2);
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
    EXPECT_EQ(run.err, "esf: error: " + missing + ": no such file\n");
}

TEST_F(CliUsageTest, HelpAndVersionStillGoToStdout) {
    const CliRun help = esf("--help");
    EXPECT_EQ(help.code, 0);
    EXPECT_NE(help.out.find("describe"), std::string::npos);
    EXPECT_EQ(help.err, "");
    const CliRun version = esf("--version");
    EXPECT_EQ(version.code, 0);
    EXPECT_NE(version.out.find("esf "), std::string::npos);
    const CliRun sub = esf("describe --help");
    EXPECT_EQ(sub.code, 0);
    EXPECT_NE(sub.out.find("--threads"), std::string::npos);
}

/// The lines of `text`.
std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

// `esf --help` is one screen: at most 40 lines, one line per command (its summary); each
// command's own --help starts with that summary and ends with the long description.
TEST_F(CliUsageTest, HelpListsEveryCommandOnOneLine) {
    const std::vector<std::string> commands = {
        "demo",     "describe",      "train",           "info",  "segment",
        "generate", "render",        "classify",        "scene", "compare",
        "eval",     "learn-weights", "generate-scenes", "live",  "record-scenes"};
    const CliRun help = esf("--help");
    ASSERT_EQ(help.code, 0);
    const std::vector<std::string> lines = lines_of(help.out);
    EXPECT_LE(lines.size(), 40u) << help.out;
    const auto first = std::find(lines.begin(), lines.end(), "Subcommands:");
    ASSERT_NE(first, lines.end()) << help.out;
    std::vector<std::string> listed;
    for (auto it = first + 1; it != lines.end() && !it->empty(); ++it) listed.push_back(*it);
    ASSERT_EQ(listed.size(), commands.size()) << help.out;
    for (std::size_t i = 0; i < commands.size(); ++i) {
        SCOPED_TRACE(commands[i]);
        const std::string& line = listed[i];
        ASSERT_EQ(line.rfind("  " + commands[i] + " ", 0), 0u) << line;
        EXPECT_LE(line.size(), 100u) << line;
        const std::string summary =
            line.substr(line.find_first_not_of(' ', commands[i].size() + 2));
        const CliRun own = esf(commands[i] + " --help");
        EXPECT_EQ(own.code, 0);
        EXPECT_EQ(own.out.rfind(summary, 0), 0u) << own.out;
        EXPECT_GT(lines_of(own.out).size(), 10u) << own.out;
    }
    // The long description of segment names the grouping it uses by default.
    EXPECT_NE(esf("segment --help").out.find("--grouping convexity"), std::string::npos);
}

}  // namespace
