// A generated scene folder: byte-identical at any thread count, a scene set that
// read_scene_set takes and that matches the frames' labels, truth.json that names every object.

#include "esf/evaluation/generated_scenes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "esf/core/error.hpp"
#include "esf/evaluation/pose_accuracy.hpp"
#include "esf/evaluation/scene_evaluation.hpp"
#include "esf/evaluation/scene_sequences.hpp"
#include "esf/evaluation/scene_truth.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/report/scene_report.hpp"
#include "esf/training/database.hpp"
#include "support/test_meshes.hpp"

namespace fs = std::filesystem;

namespace {

std::string read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
}

class GeneratedScenesTest : public ::testing::Test {
  protected:
    void SetUp() override {
        base_ = fs::temp_directory_path() /
                ("esf_generated_" +
                 std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        fs::remove_all(base_);
        root_ = base_ / "meshes";
        // Millimetre boxes (non-metric in the catalog, scaled to their category's size) and
        // metric ones.
        std::string rows = "file,category,source,model,group,extent,metric\n";
        for (int i = 0; i < 6; ++i) {
            const std::string category = i < 3 ? "box" : "block";
            const std::string name = "m" + std::to_string(i);
            fs::create_directories(root_ / category);
            const bool mm = i == 1;
            const double k = mm ? 1000.0 : 1.0;
            esf::write_ply_mesh((root_ / category / (name + ".ply")).string(),
                                esf::test::standing_box(k * (0.05 + 0.02 * i), k * 0.06, k * 0.1));
            rows += category + "/" + name + ".ply," + category + ",test," + name + ",g" +
                    std::to_string(i) + "," + (mm ? "160" : "0.15") + "," + (mm ? "no" : "yes") +
                    "\n";
        }
        std::ofstream(root_ / "catalog.csv") << rows;
    }
    void TearDown() override { fs::remove_all(base_); }

    // `scenes` generated scenes of the meshes in base_/s (seed `seed`), and a database of all
    // the meshes, quickly trained: its path.
    std::string scenes_and_database(std::size_t scenes, std::uint64_t seed) {
        esf::SceneGenerationOptions options;
        options.scenes = scenes;
        options.clutter.seed = seed;
        esf::generate_scenes(root_.string(), (base_ / "s").string(), options);
        const std::string db_path = (base_ / "db.sqlite").string();
        esf::Database db(db_path, esf::OpenMode::kWrite);
        esf::TrainingOptions training;
        training.render.level = 0;
        training.descriptor_options.samples = 5000;
        esf::train(root_.string(), db, training);
        return db_path;
    }

    fs::path base_, root_;
};

TEST_F(GeneratedScenesTest, SameFilesAtAnyThreadCountAndTruthMatchesLabels) {
    esf::SceneGenerationOptions options;
    options.scenes = 7;
    options.clutter.seed = 3;
    options.threads = 1;
    const esf::GeneratedSceneSet one =
        esf::generate_scenes(root_.string(), (base_ / "a").string(), options);
    options.threads = 2;
    const esf::GeneratedSceneSet two =
        esf::generate_scenes(root_.string(), (base_ / "b").string(), options);
    ASSERT_EQ(one.files.size(), 7u + 2u);
    EXPECT_EQ(one.models, 6u);
    for (std::size_t t = 0; t < one.per_type.size(); ++t) EXPECT_EQ(one.per_type[t], 1u);
    for (std::size_t i = 0; i < one.files.size(); ++i) {
        const fs::path name = fs::path(one.files[i]).filename();
        EXPECT_EQ(read_bytes(base_ / "a" / name), read_bytes(base_ / "b" / name)) << name;
    }

    const nlohmann::json truth = nlohmann::json::parse(read_bytes(base_ / "a" / "truth.json"));
    ASSERT_EQ(truth["scenes"].size(), 7u);
    const esf::SceneSet set = esf::read_scene_set((base_ / "a" / "scenes.csv").string());
    std::size_t rows = 0;
    for (const esf::LabelledScene& s : set.scenes) rows += s.objects.size();
    EXPECT_EQ(rows, one.labelled);
    EXPECT_GT(one.labelled, 7u);

    for (const auto& scene : truth["scenes"]) {
        const std::string file = scene["file"];
        const esf::PointCloud cloud = esf::read_pcd((base_ / "a" / file).string());
        ASSERT_EQ(cloud.width, 640u);
        ASSERT_EQ(cloud.height, 480u);
        std::map<std::uint32_t, std::size_t> pixels;
        for (const std::uint32_t label : cloud.labels) ++pixels[label];
        EXPECT_GT(pixels[1], 1000u) << file << ": the table";
        std::set<std::uint32_t> labelled;
        for (const auto& o : scene["objects"]) {
            const std::uint32_t id = o["object_id"];
            EXPECT_EQ(o["type"], scene["type"]);
            EXPECT_TRUE(fs::exists(root_ / o["model"].get<std::string>()));
            // The millimetre model is scaled to metres: its pose carries the scale.
            const double scale = o["scale"];
            const bool mm = o["model"] == "box/m1.ply";
            EXPECT_NEAR(scale, mm ? 0.15 / 160.0 : 1.0, 1e-12);
            Eigen::Matrix3d linear;
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) linear(r, c) = o["pose"][4 * r + c];
            EXPECT_NEAR(linear.determinant(), scale * scale * scale, 1e-9);
            if (o["labelled"]) {
                labelled.insert(id);
                EXPECT_EQ(pixels[10 * id], o["pixels"].get<std::size_t>());
            } else {
                EXPECT_EQ(pixels.count(10 * id), 0u);
            }
        }
        for (const auto& s : set.scenes)
            if (fs::path(s.file).filename() == file) {
                std::set<std::uint32_t> listed;
                for (const auto& o : s.objects) listed.insert(o.object_id);
                EXPECT_EQ(listed, labelled) << file;
                EXPECT_EQ(s.type, scene["type"].get<std::string>());
            }
    }
}

TEST_F(GeneratedScenesTest, TheTruthReadsBackAndABrokenOneIsRefusedByName) {
    esf::SceneGenerationOptions options;
    options.scenes = 3;
    options.clutter.seed = 5;
    esf::generate_scenes(root_.string(), (base_ / "t").string(), options);
    const std::string csv = (base_ / "t" / "scenes.csv").string();
    const std::optional<esf::SceneTruth> truth = esf::read_scene_truth(csv);
    ASSERT_TRUE(truth);
    EXPECT_EQ(fs::path(truth->root), root_);
    const nlohmann::json json = nlohmann::json::parse(read_bytes(base_ / "t" / "truth.json"));
    std::size_t objects = 0;
    for (const auto& scene : json["scenes"])
        for (const auto& o : scene["objects"]) {
            ++objects;
            const auto it = truth->objects.find({scene["file"], o["object_id"]});
            ASSERT_NE(it, truth->objects.end());
            EXPECT_EQ(it->second.model, o["model"].get<std::string>());
            EXPECT_EQ(it->second.class_name, o["class"].get<std::string>());
            EXPECT_EQ(it->second.visible, o["visible"].get<double>());
            for (int k = 0; k < 16; ++k)
                EXPECT_EQ(it->second.pose(k / 4, k % 4), o["pose"][k].get<double>());
        }
    EXPECT_EQ(truth->objects.size(), objects);

    // No truth beside a scene set: nothing to judge poses by.
    fs::create_directories(base_ / "none");
    EXPECT_FALSE(esf::read_scene_truth((base_ / "none" / "scenes.csv").string()));
    // A pose of 15 numbers, or a truncated file: refused, naming the file.
    nlohmann::json broken = json;
    broken["scenes"][0]["objects"][0]["pose"].erase(0);
    std::ofstream(base_ / "t" / "truth.json") << broken.dump();
    try {
        esf::read_scene_truth(csv);
        FAIL() << "a pose of 15 numbers was read";
    } catch (const esf::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("truth.json"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("15 numbers"), std::string::npos) << e.what();
    }
    const std::string text = json.dump();
    std::ofstream(base_ / "t" / "truth.json") << text.substr(0, text.size() / 2);
    EXPECT_THROW(esf::read_scene_truth(csv), esf::IoError);
    // Hostile values: a negative id, a visible share above 1, a pose beyond double's range.
    const auto refused = [&](const std::string& file, const std::string& reason) {
        std::ofstream(base_ / "t" / "truth.json") << file;
        try {
            esf::read_scene_truth(csv);
            ADD_FAILURE() << "read: " << reason;
        } catch (const esf::IoError& e) {
            EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
        }
    };
    nlohmann::json hostile = json;
    hostile["scenes"][0]["objects"][0]["object_id"] = -3;
    refused(hostile.dump(), "an object id of -3");
    hostile = json;
    hostile["scenes"][0]["objects"][0]["visible"] = 1.5;
    refused(hostile.dump(), "a visible share of 1.5");
    hostile = json;
    hostile["scenes"][0]["objects"][0]["pose"][3] = 7.25;
    std::string overflowing = hostile.dump();
    const std::size_t at = overflowing.find("7.25");
    ASSERT_NE(at, std::string::npos);
    refused(overflowing.replace(at, 4, "1e999"), "number overflow");
}

TEST_F(GeneratedScenesTest, FoldsKeepScenesAwayFromTheTrainingSide) {
    esf::SceneGenerationOptions options;
    options.scenes = 4;
    options.groups.fold = 0;
    options.groups.folds = 2;
    const auto set = esf::generate_scenes(root_.string(), (base_ / "f").string(), options);
    std::set<std::string> used;
    const nlohmann::json truth = nlohmann::json::parse(read_bytes(base_ / "f" / "truth.json"));
    for (const auto& scene : truth["scenes"])
        for (const auto& o : scene["objects"]) used.insert(o["model"]);
    esf::GroupSelection train = options.groups;
    train.other_folds = true;
    for (const auto& plan : esf::plan_models(root_.string(), "", true, train))
        EXPECT_FALSE(used.count(plan.file.file)) << plan.file.file;
    EXPECT_LT(set.models, 6u);
}

TEST_F(GeneratedScenesTest, RejectsBadRequests) {
    esf::SceneGenerationOptions options;
    options.scenes = 0;
    EXPECT_THROW(esf::generate_scenes(root_.string(), (base_ / "x").string(), options),
                 std::invalid_argument);
    options.scenes = 1;
    options.groups.only = {"none-such"};
    EXPECT_THROW(esf::generate_scenes(root_.string(), (base_ / "x").string(), options),
                 std::invalid_argument);
}

}  // namespace

TEST_F(GeneratedScenesTest, PosesAreJudgedAgainstTheTruthAndVerificationPlacesTheModels) {
    const std::string db_path = scenes_and_database(7, 2);
    const esf::SceneSet set = esf::read_scene_set((base_ / "s" / "scenes.csv").string());
    esf::RecognizerOptions knn_only;
    knn_only.verify = false;
    const esf::SceneEvaluationReport plain =
        esf::evaluate_scenes(esf::Recognizer(db_path, knn_only), set);
    // By default the recognizer verifies with the surfaces training stored; sampled again from
    // the meshes (same seed), they give the same classes, models and poses.
    const esf::Recognizer stored(db_path);
    EXPECT_TRUE(stored.verifies());
    EXPECT_EQ(stored.info().verification, "stored surfaces");
    const esf::SceneEvaluationReport verified = esf::evaluate_scenes(stored, set);
    esf::RecognizerOptions from_meshes;
    from_meshes.verification_meshes = root_.string();
    const esf::SceneEvaluationReport resampled =
        esf::evaluate_scenes(esf::Recognizer(db_path, from_meshes), set);
    ASSERT_EQ(verified.objects.size(), resampled.objects.size());
    for (std::size_t i = 0; i < verified.objects.size(); ++i) {
        const esf::SceneObjectOutcome& x = verified.objects[i];
        const esf::SceneObjectOutcome& y = resampled.objects[i];
        EXPECT_EQ(x.predicted_model, y.predicted_model);
        ASSERT_EQ(x.pose.has_value(), y.pose.has_value());
        if (x.pose) {
            EXPECT_EQ(*x.pose, *y.pose);
        }
    }
    EXPECT_EQ(plain.truth, fs::absolute(root_).lexically_normal().string());
    const esf::SceneTypeSummary& a = plain.types.back();
    const esf::SceneTypeSummary& b = verified.types.back();
    ASSERT_EQ(a.type, "all");
    EXPECT_GT(a.posed, 5u);
    EXPECT_EQ(a.posed, b.posed);
    // A training view's pose is not where the object stands; the fitted pose is, for the
    // objects named with their own model.
    EXPECT_EQ(a.pose_correct, 0u);
    std::size_t own_model = 0, placed = 0;
    for (const esf::SceneObjectOutcome& o : verified.objects) {
        if (!o.pose_judged || !std::isfinite(o.add_s)) continue;
        ++own_model;
        placed += o.pose_correct;
    }
    // Three in four: the objects named with their own model include ones barely seen (here 7
    // of 9, one at 0.104 d).
    EXPECT_GT(own_model, 0u);
    EXPECT_GE(static_cast<double>(placed), 0.75 * static_cast<double>(own_model));
    EXPECT_EQ(b.pose_correct, placed);
    // Whatever model was named, the own model is scored under the pose found: the same ADD-S
    // where the own model was named, a finite one for every found object with a pose, and no
    // fewer poses right.
    std::size_t any_model = 0;
    for (const esf::SceneObjectOutcome& o : verified.objects) {
        if (!o.pose_judged) continue;
        const bool found = o.segmentation.outcome == esf::SegmentOutcome::kFound;
        EXPECT_EQ(std::isfinite(o.add_s_any_model), found && o.pose.has_value());
        if (std::isfinite(o.add_s)) {
            EXPECT_EQ(o.add_s_any_model, o.add_s);
        }
        EXPECT_EQ(o.pose_correct_any_model, o.add_s_any_model < esf::kAddSThreshold);
        any_model += o.pose_correct_any_model;
    }
    EXPECT_GE(any_model, placed);
    EXPECT_EQ(b.pose_correct_any_model, any_model);
    // The classes' rows add up to the overall one.
    std::size_t class_objects = 0, class_correct = 0;
    for (const esf::SceneClassSummary& c : verified.classes) {
        class_objects += c.objects;
        class_correct += c.correct;
    }
    EXPECT_EQ(class_objects, b.labelled);
    EXPECT_EQ(class_correct, b.correct);
    EXPECT_EQ(verified.classes.size(), 2u);  // box and block
    // Boxes have symmetries (half turns): no rotation error is given for them.
    for (const esf::SceneObjectOutcome& o : verified.objects) EXPECT_FALSE(o.rotation_error);
    EXPECT_TRUE(b.rotation_errors.empty());
    EXPECT_TRUE(std::isnan(b.rotation_median()));
    // Reports carry the pose columns.
    const nlohmann::json json = nlohmann::json::parse(esf::scene_report_json(verified));
    EXPECT_EQ(json["types"].back()["pose_correct"].get<std::size_t>(), placed);
    EXPECT_EQ(json["types"].back()["pose_correct_any_model"].get<std::size_t>(), any_model);
    EXPECT_TRUE(json["types"].back()["rotation_median_deg"].is_null());
    EXPECT_NE(esf::scene_report_html(verified, "t").find("ADD-S &lt; 0.1 d"), std::string::npos);
    esf::SceneEvaluationReport without_truth = plain;
    without_truth.truth.clear();
    EXPECT_EQ(esf::scene_report_html(without_truth, "t").find("ADD-S"), std::string::npos);
}

TEST_F(GeneratedScenesTest, RotationErrorsAreGivenForModelsWithoutSymmetry) {
    // Boxes with a knob on one end of a side (no turn maps them onto themselves) join the boxes.
    std::string rows;
    for (int i = 0; i < 2; ++i) {
        const std::string name = "knob" + std::to_string(i);
        fs::create_directories(root_ / "knobbed");
        esf::write_ply_mesh((root_ / "knobbed" / (name + ".ply")).string(),
                            esf::test::knobbed_box(0.12 + 0.03 * i, 0.07, 0.09, 0.035));
        rows += "knobbed/" + name + ".ply,knobbed,test," + name + ",k" + std::to_string(i) +
                ",0.15,yes\n";
    }
    std::ofstream(root_ / "catalog.csv", std::ios::app) << rows;
    const std::string db_path = scenes_and_database(8, 4);
    const esf::SceneSet set = esf::read_scene_set((base_ / "s" / "scenes.csv").string());
    const esf::SceneEvaluationReport report = esf::evaluate_scenes(esf::Recognizer(db_path), set);
    const esf::SceneTruth truth = *esf::read_scene_truth(set.path);
    std::size_t rotations = 0, near = 0;
    for (const esf::SceneObjectOutcome& o : report.objects) {
        const esf::TruthObject& t =
            truth.objects.at({fs::path(o.scene).filename().string(), o.segmentation.object_id});
        // Only knobbed models named with their own model, posed, have one.
        const bool own = o.pose_judged && std::isfinite(o.add_s);
        EXPECT_EQ(o.rotation_error.has_value(), own && t.class_name == "knobbed")
            << o.scene << " " << o.segmentation.object_id;
        if (!o.rotation_error) continue;
        ++rotations;
        EXPECT_EQ(*o.rotation_error, esf::rotation_error_degrees(t.pose, o.pose->cast<double>()));
        near += *o.rotation_error < 10.0;
    }
    ASSERT_GT(rotations, 0u);
    // The fits find the knob: most of them turned less than 10 degrees from the truth.
    EXPECT_GE(2 * near, rotations);
    const esf::SceneTypeSummary& all = report.types.back();
    EXPECT_EQ(all.rotation_errors.size(), rotations);
    EXPECT_TRUE(std::isfinite(all.rotation_median()));
    const nlohmann::json json = nlohmann::json::parse(esf::scene_report_json(report));
    EXPECT_EQ(json["types"].back()["rotations"].get<std::size_t>(), rotations);
    EXPECT_DOUBLE_EQ(json["types"].back()["rotation_median_deg"].get<double>(),
                     all.rotation_median());
    std::size_t rows_with_rotation = 0;
    for (const nlohmann::json& o : json["objects"])
        rows_with_rotation += !o["rotation_error_deg"].is_null();
    EXPECT_EQ(rows_with_rotation, rotations);
    EXPECT_NE(esf::scene_report_html(report, "t").find("median rotation error"), std::string::npos);
}

TEST_F(GeneratedScenesTest, SequenceScoresBoundFusionAndReportEachFrameObjectInOrder) {
    const std::string db = scenes_and_database(1, 4);
    esf::SceneSequenceOptions options;
    options.sequences = 2;
    options.frames = 4;
    options.clutter.seed = 5;
    options.clutter.types = {esf::ClutterType::kIsolated, esf::ClutterType::kMixed};
    const esf::SceneSequenceSet set =
        esf::generate_scene_sequences(root_.string(), (base_ / "q").string(), options);
    ASSERT_EQ(set.folders.size(), 2u);

    const esf::Recognizer recognizer(db);
    esf::SequenceFusionOptions fusion;
    fusion.checkpoints = {1, 2, 4};
    std::vector<esf::SequenceFrameObject> seen;
    std::size_t found = 0, single_right = 0;
    fusion.on_object = [&](const esf::SequenceFrameObject& o) {
        seen.push_back(o);
        if (!o.found) return;
        ++found;
        single_right += o.found->classified() && o.found->classification.class_name == o.true_class;
        EXPECT_NE(o.track, 0u);
        EXPECT_FALSE(o.track_class.empty());
        EXPECT_NE(o.cloud, nullptr);
    };
    const esf::SequenceFusionResult r =
        esf::evaluate_scene_sequences(recognizer, (base_ / "q").string(), fusion);

    // Every true object of every frame is reported once, sequence by sequence, frame by frame.
    ASSERT_EQ(seen.size(), r.frame_objects);
    ASSERT_GT(found, 0u);
    EXPECT_EQ(single_right, r.frame_single_right);
    for (std::size_t i = 1; i < seen.size(); ++i)
        EXPECT_TRUE(std::pair(seen[i - 1].sequence, seen[i - 1].frame) <=
                    std::pair(seen[i].sequence, seen[i].frame));
    EXPECT_EQ(seen.back().sequence, 1u);
    EXPECT_EQ(seen.back().frame, 3u);
    std::set<std::pair<std::size_t, std::uint32_t>> objects;
    for (const esf::SequenceFrameObject& o : seen) objects.insert({o.sequence, o.object_id});
    EXPECT_EQ(r.objects, objects.size());
    EXPECT_LE(r.objects_rarely_right + r.objects_mostly_right, r.objects);

    // One of its frames so far is right at least as often as the frame alone and the track;
    // after one frame, exactly when that frame is.
    EXPECT_GE(r.frame_any_right, r.frame_single_right);
    EXPECT_GE(r.frame_any_right, r.frame_fused_right);
    ASSERT_FALSE(r.points.empty());
    EXPECT_EQ(r.points.front().frames, 1u);
    EXPECT_EQ(r.points.front().any_right, r.points.front().single_right);
    for (const esf::SequenceFusionPoint& p : r.points) {
        EXPECT_GE(p.any_right, p.single_right);
        EXPECT_LE(p.any_right, p.objects);
    }
}
