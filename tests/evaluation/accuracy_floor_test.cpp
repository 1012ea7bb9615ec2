// Accuracy floor on real data (issue: evaluation like the paper): trains the default pipeline
// (ESF + surface angle histograms, cameras of the upper half of the view sphere at 0.6 to 1.2 m)
// on all shared meshes (../shared/data/meshes, 185 models x 44 views) and classifies the 116
// segmented real Kinect / stereo views of real/labels.csv from the mOSD learn split and PCL
// (10-NN: the ten nearest models, each by its nearest view); the 113 views of the mOSD test
// split's mixed and complex scenes, added later, have floors of their own. The result is
// deterministic (seeded, independent of the thread count); BENCHMARKS.md records what it
// reaches: 84.5 % 1-NN and 95.7 % 10-NN per sample, 72.8 % 1-NN as the mean over classes. The
// floors sit a few points below, so a regression fails CI. About half a minute on 2 cores (the
// training dominates).

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "esf/evaluation/evaluation.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"
#include "support/test_data.hpp"

namespace esf {
namespace {

namespace fs = std::filesystem;

constexpr double kFloorTop1 = 0.77;       // reached: 0.845
constexpr double kFloorTop10 = 0.92;      // reached: 0.957
constexpr double kFloorClassTop1 = 0.66;  // reached: 0.728
constexpr double kPclTop1 = 0.51;         // PCL's own pipeline on the same data
constexpr double kPclTop10 = 0.77;

TEST(AccuracyFloor, EsfOnRealViewsBeatsThePclPipeline) {
    ESF_REQUIRE_DATA("meshes/catalog.csv");
    ESF_REQUIRE_DATA("real/labels.csv");
    const fs::path dir =
        fs::temp_directory_path() / ("esf_accuracy_floor_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string db_path = (dir / "meshes.sqlite").string();
    {
        Database db(db_path, OpenMode::kWrite);
        const TrainingResult trained =
            train(test::data_file("meshes").string(), db, TrainingOptions{});
        EXPECT_EQ(trained.models_trained, 185u);
        EXPECT_EQ(trained.models_failed, 0u);
    }
    const Recognizer recognizer(db_path);
    const TestSet all = read_test_set(test::data_file("real/labels.csv").string());
    TestSet test_set = all, cluttered = all;
    test_set.samples.clear();
    cluttered.samples.clear();
    for (const auto& sample : all.samples)
        (sample.file.find("mosd_test") == std::string::npos ? test_set : cluttered)
            .samples.push_back(sample);
    const EvaluationReport report = evaluate_test_set(recognizer, test_set, {});
    const EvaluationReport mixed = evaluate_test_set(recognizer, cluttered, {});
    fs::remove_all(dir);

    // Views of the mixed and complex test scenes (reached: 69.0 % 1-NN, 98.2 % 10-NN, 66.9 %
    // per class).
    EXPECT_EQ(mixed.samples, 113u);
    EXPECT_EQ(mixed.failed, 0u);
    EXPECT_GE(mixed.top1, 0.60);
    EXPECT_GE(mixed.topk, 0.88);
    EXPECT_GE(mixed.class_top1, 0.66);

    EXPECT_EQ(report.samples, 116u);
    EXPECT_EQ(report.failed, 0u);
    EXPECT_GE(report.top1, kFloorTop1);
    EXPECT_GE(report.topk, kFloorTop10);
    EXPECT_GE(report.class_top1, kFloorClassTop1);
    EXPECT_GT(report.top1, kPclTop1 + 0.05) << "no longer clearly better than PCL's pipeline";
    EXPECT_GE(report.topk, kPclTop10);
    RecordProperty("top1", std::to_string(report.top1));
    RecordProperty("top10", std::to_string(report.topk));
    RecordProperty("class_top1", std::to_string(report.class_top1));
}

}  // namespace
}  // namespace esf
