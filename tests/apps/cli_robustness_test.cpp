// Runs the built `esf` binary (ESF_CLI) on hostile options and inputs: thread counts far above
// the cores, negative seeds, two trainings of one database, stale learned weights, camera
// distances Embree cannot take, a training root with a symbolic link loop, usage errors.
// Each gives one clear line on stderr and the documented exit code, or a correct result.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "esf/core/parallel.hpp"
#include "esf/training/database.hpp"
#include "support/cli_run.hpp"
#include "support/error_of.hpp"

namespace fs = std::filesystem;
using esf::test::CliRun;
using esf::test::quoted;

namespace {

std::size_t lines(const std::string& s) {
    std::size_t n = 0;
    for (const char c : s) n += c == '\n';
    return n;
}

/// One generated mug and bowl, a database trained on them (--level 0: 20 views each) and one
/// rendered view of the mug with a test set listing it; shared by the tests of the suite.
class CliRobustnessTest : public ::testing::Test {
  protected:
    static void SetUpTestSuite() {
        dir() = fs::temp_directory_path() / ("esf_cli_robustness_" + std::to_string(::getpid()));
        fs::remove_all(dir());
        fs::create_directories(dir());
        setup_error() = run("generate -o " + quoted(dir() / "root") +
                            " --per-class 1 --categories mug,bowl --seed 3")
                            .err;
        if (!fs::exists(dir() / "root" / "mug" / "gen_mug_000.ply")) return;
        const CliRun train =
            run("train " + quoted(dir() / "root") + " -o " + quoted(db()) + " --level 0");
        if (train.code != 0) {
            setup_error() = "train: " + train.err;
            return;
        }
        const CliRun render = run("render " + quoted(mesh()) + " -o " + quoted(dir() / "views") +
                                  " --level 0 --seed 11");
        if (render.code != 0) {
            setup_error() = "render: " + render.err;
            return;
        }
        std::ofstream(dir() / "test.csv") << "file,class\nviews/view_003.pcd,mug\n";
        setup_error().clear();
    }
    static void TearDownTestSuite() { fs::remove_all(dir()); }
    void SetUp() override { ASSERT_TRUE(setup_error().empty()) << setup_error(); }

    static fs::path& dir() {
        static fs::path d;
        return d;
    }
    static std::string& setup_error() {
        static std::string e = "not set up";
        return e;
    }
    static std::string db() { return (dir() / "db.sqlite").string(); }
    static std::string mesh() { return (dir() / "root" / "mug" / "gen_mug_000.ply").string(); }
    static std::string view() { return (dir() / "views" / "view_003.pcd").string(); }
    static CliRun run(const std::string& args) { return esf::test::run_esf(args, dir()); }
    static std::string path(const std::string& name) { return (dir() / name).string(); }
};

TEST_F(CliRobustnessTest, ThreadCountsAboveFourTimesTheCoresAreCappedWithAWarning) {
    const int cap = esf::max_threads();
    const std::string warning = "esf: warning: --threads 70000 is above 4 x the " +
                                std::to_string(cap / 4) + " cores; using " + std::to_string(cap) +
                                "\n";
    const std::string t = " --threads 70000";
    fs::remove(path("capped.sqlite"));
    const std::vector<std::string> commands = {
        "train " + quoted(dir() / "root") + " -o " + quoted(path("capped.sqlite")) + " --level 0",
        "eval " + quoted(db()) + " " + quoted(dir() / "test.csv"),
        "classify " + quoted(db()) + " " + quoted(view()),
        "describe " + quoted(view()),
        "segment " + quoted(view()) + " -o " + quoted(dir() / "segments"),
        "scene " + quoted(db()) + " " + quoted(view()),
    };
    for (const std::string& command : commands) {
        const CliRun r = run(command + t);
        // The crash this guards against was a segmentation fault inside TBB; segment and scene
        // may find no table in a lone view (exit 2), the others succeed.
        const bool segments = command.rfind("segment", 0) == 0 || command.rfind("scene", 0) == 0;
        if (segments)
            EXPECT_TRUE(r.code == 0 || r.code == 2) << command << "\n" << r.err;
        else
            EXPECT_EQ(r.code, 0) << command << "\n" << r.err;
        EXPECT_EQ(r.err.rfind(warning, 0), 0u) << command << "\n" << r.err;
    }
    // A huge count too, and a cap reached exactly is no warning.
    const CliRun huge = run("describe " + quoted(view()) + " --threads 99999999999999999999");
    EXPECT_EQ(huge.code, 0) << huge.err;
    EXPECT_CONTAINS(huge.err, "esf: warning: --threads (a huge count) is above 4 x the ");
    const CliRun exact = run("describe " + quoted(view()) + " --threads " + std::to_string(cap));
    EXPECT_EQ(exact.code, 0) << exact.err;
    EXPECT_EQ(exact.err, "");
    const CliRun negative = run("describe " + quoted(view()) + " --threads -3");
    EXPECT_EQ(negative.code, 1);
    EXPECT_EQ(negative.err.rfind("esf: error: --threads", 0), 0u) << negative.err;
    EXPECT_EQ(lines(negative.err), 1u) << negative.err;
}

TEST_F(CliRobustnessTest, NegativeSeedsAreRefusedInOneLine) {
    const std::vector<std::string> commands = {
        "describe " + quoted(view()),
        "train " + quoted(dir() / "root") + " -o " + quoted(path("never.sqlite")),
        "render " + quoted(mesh()) + " -o " + quoted(path("never")),
        "generate -o " + quoted(path("never")),
        "segment " + quoted(view()) + " -o " + quoted(path("never")),
    };
    for (const std::string& command : commands) {
        const CliRun r = run(command + " --seed -1");
        EXPECT_EQ(r.code, 1) << command << "\n" << r.err;
        EXPECT_EQ(r.err.rfind("esf: error: --seed: ", 0), 0u) << command << "\n" << r.err;
        EXPECT_CONTAINS(r.err, "seed must be a non-negative integer, got -1");
        EXPECT_EQ(lines(r.err), 1u) << r.err;
    }
    EXPECT_FALSE(fs::exists(path("never.sqlite")));
    EXPECT_FALSE(fs::exists(path("never")));
}

TEST_F(CliRobustnessTest, ASelectionOfNoModelsFailsBeforeADatabaseIsCreated) {
    for (const std::string selection :
         {"--categories pear", "--groups none-such", "--categories mug,pear"}) {
        const fs::path out = path("unselected.sqlite");
        fs::remove(out);
        const CliRun r =
            run("train " + quoted(dir() / "root") + " -o " + quoted(out) + " " + selection);
        EXPECT_EQ(r.code, 2) << selection;
        EXPECT_EQ(r.err.rfind("esf: error: no ", 0), 0u) << r.err;
        EXPECT_EQ(lines(r.err), 1u) << r.err;
        EXPECT_FALSE(fs::exists(out)) << selection << ": an empty database was left behind";
    }
}

TEST_F(CliRobustnessTest, UsageErrorsAreOneLine) {
    const std::vector<std::string> usage_errors = {
        "frobnicate", "classify " + quoted(db()) + " " + quoted(view()) + " -k 0", "describe"};
    for (const std::string& args : usage_errors) {
        const CliRun r = run(args);
        EXPECT_EQ(r.code, 1) << args;
        EXPECT_EQ(r.err.rfind("esf: error: ", 0), 0u) << r.err;
        EXPECT_EQ(lines(r.err), 1u) << r.err;
    }
    const CliRun help = run("--help");
    EXPECT_EQ(help.code, 0);
    EXPECT_CONTAINS(help.out, "train");
}

TEST_F(CliRobustnessTest, ASecondTrainingOfTheSameDatabaseIsRefused) {
    const std::string target = path("busy.sqlite");
    fs::remove(target);
    {
        // Another training holds the new database.
        const esf::Database first(target, esf::OpenMode::kWrite);
        const CliRun second = run("train " + quoted(dir() / "root") + " -o " + quoted(target) +
                                  " --level 0 --seed 5");
        EXPECT_EQ(second.code, 2);
        EXPECT_EQ(second.err,
                  "esf: error: " + target + ": database is in use by another training\n");
        // learn-weights checks before it learns.
        const CliRun learn = run("learn-weights " + quoted(target));
        EXPECT_EQ(learn.code, 2);
        EXPECT_CONTAINS(learn.err, "database is in use by another training");
    }
    // Nothing of the refused run is in it.
    const esf::Database after(target);
    EXPECT_TRUE(after.models().empty());
    EXPECT_TRUE(after.settings().empty());
}

TEST_F(CliRobustnessTest, StaleWeightsAreIgnoredWithAWarning) {
    const std::string copy = path("weights.sqlite");
    fs::copy_file(db(), copy, fs::copy_options::overwrite_existing);
    const CliRun learn = run("learn-weights " + quoted(copy) + " --iterations 1 --max-queries 10");
    ASSERT_EQ(learn.code, 0) << learn.err;
    const CliRun fresh = run("classify " + quoted(copy) + " " + quoted(view()));
    EXPECT_EQ(fresh.code, 0) << fresh.err;
    EXPECT_EQ(fresh.err, "");

    // A category added by training: the weights no longer fit and are not applied.
    const CliRun gen = run("generate -o " + quoted(dir() / "root2") +
                           " --per-class 1 --categories mug,bowl,bottle --seed 3");
    ASSERT_EQ(gen.code, 0) << gen.err;
    const CliRun more =
        run("train " + quoted(dir() / "root2") + " -o " + quoted(copy) + " --level 0");
    ASSERT_EQ(more.code, 0) << more.err;
    for (const std::string command : {"classify", "scene"}) {
        const CliRun stale = run(command + " " + quoted(copy) + " " + quoted(view()));
        EXPECT_EQ(stale.err.rfind("esf: warning: " + copy +
                                      ": the learned weights predate the database's last training "
                                      "and are ignored; run esf learn-weights again\n",
                                  0),
                  0u)
            << stale.err;
    }
    const CliRun info = run("info " + quoted(copy));
    EXPECT_CONTAINS(info.out, "weights: stale (ignored; learn them again)");
    const esf::Database stored(copy);
    EXPECT_TRUE(stored.weights_are_stale());
    EXPECT_EQ(stored.weights(), std::nullopt);
    EXPECT_NE(stored.stored_weights(), std::nullopt);
}

TEST_F(CliRobustnessTest, RenderRefusesCamerasEmbreeCannotTake) {
    for (const std::string option : {"--distance 1e20", "--fx 1e30 --fy 1e30", "--fx 1e-30"}) {
        const CliRun r =
            run("render " + quoted(mesh()) + " -o " + quoted(path("far")) + " --level 0 " + option);
        EXPECT_EQ(r.code, 2) << option << "\n" << r.err;
        EXPECT_EQ(r.err.rfind("esf: error: ", 0), 0u) << r.err;
        EXPECT_EQ(lines(r.err), 1u) << r.err;
    }
}

TEST_F(CliRobustnessTest, ASymbolicLinkLoopInATrainingRootIsReportedAndTrainingGoesOn) {
    const fs::path root = dir() / "looping_root";
    fs::create_directories(root / "mug");
    fs::copy_file(mesh(), root / "mug" / "good.ply", fs::copy_options::overwrite_existing);
    fs::create_symlink("loop.ply", root / "mug" / "loop.ply");
    fs::create_symlink("spin", root / "spin");
    const std::string target = path("looping.sqlite");
    fs::remove(target);
    const CliRun r = run("train " + quoted(root) + " -o " + quoted(target) + " --level 0");
    EXPECT_EQ(r.code, 2) << r.err;  // a model failed
    EXPECT_CONTAINS(r.err, "loop.ply: cannot read: ");
    const esf::Database trained(target);
    EXPECT_EQ(trained.model_status("mug", "good"), esf::ModelStatus::kComplete);
    EXPECT_EQ(trained.model_status("mug", "loop"), esf::ModelStatus::kFailed);
}

}  // namespace
