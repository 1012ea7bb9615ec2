#include "esf/evaluation/scene_evaluation.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <stdexcept>

#include "core/csv.hpp"
#include "core/elapsed_time.hpp"
#include "esf/core/error.hpp"
#include "esf/evaluation/pose_accuracy.hpp"
#include "esf/evaluation/scene_truth.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/recognition/pose_verification.hpp"

namespace esf {

namespace {

namespace fs = std::filesystem;

using detail::milliseconds_since;

double ratio(std::size_t a, std::size_t b) {
    return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0;
}

}  // namespace

double SceneTypeSummary::found_rate() const { return ratio(found, objects); }
double SceneTypeSummary::end_to_end() const { return ratio(correct, labelled); }
double SceneTypeSummary::pose_rate() const { return ratio(pose_correct, posed); }

double SceneClassSummary::found_rate() const { return ratio(found, objects); }
double SceneClassSummary::end_to_end() const { return ratio(correct, objects); }

std::vector<SceneClassSummary> summarize_classes(std::span<const SceneObjectOutcome> objects) {
    std::map<std::string, SceneClassSummary> classes;
    std::map<std::string, std::map<std::string, std::size_t>> wrong;  // class -> name -> count
    for (const SceneObjectOutcome& o : objects) {
        if (o.true_class.empty()) continue;
        SceneClassSummary& c = classes[o.true_class];
        ++c.objects;
        if (o.segmentation.outcome != SegmentOutcome::kFound) continue;
        ++c.found;
        c.correct += o.correct;
        if (!o.correct) ++wrong[o.true_class][o.predicted_class];
    }
    std::vector<SceneClassSummary> out;
    for (auto& [name, c] : classes) {
        c.class_name = name;
        for (const auto& [predicted, count] : wrong[name])
            if (count > c.confused_count) {
                c.confused_with = predicted.empty() ? "(none)" : predicted;
                c.confused_count = count;
            }
        out.push_back(c);
    }
    return out;
}

double SceneTypeSummary::rotation_median() const {
    if (rotation_errors.empty()) return std::numeric_limits<double>::quiet_NaN();
    std::vector<double> sorted = rotation_errors;
    std::sort(sorted.begin(), sorted.end());
    const std::size_t n = sorted.size();
    return n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
}

namespace {

// Each true model, loaded once: points on its surface (mesh file coordinates) and whether it
// has a symmetry (has_symmetry).
class TrueModels {
  public:
    struct Model {
        Points points;
        bool symmetric = false;
    };
    explicit TrueModels(std::string root) : root_(std::move(root)) {}
    const Model& of(const std::string& model) {
        auto it = models_.find(model);
        if (it == models_.end()) {
            const Mesh mesh = load_mesh((fs::path(root_) / model).string());
            it = models_
                     .emplace(model, Model{sample_model_surface(mesh, 1.0, kPoints, 0).points,
                                           has_symmetry(mesh)})
                     .first;
        }
        return it->second;
    }

  private:
    static constexpr std::size_t kPoints = 400;
    std::string root_;
    std::map<std::string, Model> models_;
};

}  // namespace

SceneSet read_scene_set(std::istream& in, const std::string& path) {
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw IoError(file_message(path, 0, "read failed"));
    const std::vector<detail::CsvRecord> records = detail::parse_csv(text, path);
    if (records.empty())
        throw IoError(file_message(
            path, 0, "empty file (expected a header with scene_file, object_id and class)"));
    const detail::CsvRecord& header = records.front();
    const std::size_t none = header.fields.size();
    const std::size_t file_column = detail::column_of(header, "scene_file");
    const std::size_t id_column = detail::column_of(header, "object_id");
    const std::size_t class_column = detail::column_of(header, "class");
    const std::size_t type_column = detail::column_of(header, "scene_type");
    for (const auto& [column, name] :
         {std::pair{file_column, "scene_file"}, std::pair{id_column, "object_id"},
          std::pair{class_column, "class"}})
        if (column == none)
            throw IoError(file_message(path, header.line,
                                       std::string("the header has no '") + name + "' column"));
    std::size_t needed = std::max({file_column, id_column, class_column}) + 1;
    if (type_column != none) needed = std::max(needed, type_column + 1);
    const fs::path base = fs::path(path).parent_path();

    SceneSet set;
    set.path = path;
    std::map<std::string, std::size_t> scene_of;
    for (std::size_t r = 1; r < records.size(); ++r) {
        const detail::CsvRecord& record = records[r];
        auto fail = [&](const std::string& why) {
            throw IoError(file_message(path, record.line, why));
        };
        if (record.fields.size() < needed)
            fail(std::to_string(record.fields.size()) + " fields, the header needs at least " +
                 std::to_string(needed));
        const std::string file = detail::trim(record.fields[file_column]);
        const std::string id_text = detail::trim(record.fields[id_column]);
        const std::string class_name = detail::trim(record.fields[class_column]);
        const std::string type =
            type_column == none ? std::string() : detail::trim(record.fields[type_column]);
        if (file.empty()) fail("empty scene_file");
        if (class_name.empty()) fail("empty class for object " + id_text + " of " + file);
        std::uint32_t id = 0;
        {
            std::size_t used = 0;
            unsigned long value = 0;
            try {
                value = std::stoul(id_text, &used);
            } catch (const std::exception&) {
                used = 0;
            }
            if (id_text.empty() || used != id_text.size() || id_text[0] == '-' ||
                value > 0xFFFFFFFFul)
                fail("object_id is not a non-negative integer: '" + id_text + "'");
            id = static_cast<std::uint32_t>(value);
        }
        const fs::path p(file);
        const std::string resolved = p.is_absolute() || base.empty() ? file : (base / p).string();
        auto [it, inserted] = scene_of.try_emplace(resolved, set.scenes.size());
        if (inserted) set.scenes.push_back({resolved, type, {}});
        LabelledScene& scene = set.scenes[it->second];
        if (scene.type != type)
            fail("scene " + file + " has two types: '" + scene.type + "' and '" + type + "'");
        for (const SceneObjectLabel& o : scene.objects)
            if (o.object_id == id && o.class_name != class_name)
                fail("object " + id_text + " of " + file + " has two classes: '" + o.class_name +
                     "' and '" + class_name + "'");
        scene.objects.push_back({id, class_name});
    }
    if (set.scenes.empty())
        throw IoError(file_message(path, header.line, "no scenes after the header"));
    return set;
}

SceneSet read_scene_set(const std::string& csv) {
    std::ifstream in(csv, std::ios::binary);
    if (!in) throw IoError(file_message(csv, 0, "cannot open scene set"));
    return read_scene_set(in, csv);
}

namespace {

// ADD-S of a found object whose model the database holds, at least half visible.
void judge_pose(const SceneTruth& truth, TrueModels& models,
                const std::set<std::pair<std::string, std::string>>& held,
                SceneObjectOutcome& outcome) {
    const auto it = truth.objects.find(
        {fs::path(outcome.scene).filename().string(), outcome.segmentation.object_id});
    if (it == truth.objects.end()) return;
    const TruthObject& t = it->second;
    const std::string name = fs::path(t.model).stem().string();
    if (t.visible < 0.5 || !held.count({t.class_name, name})) return;
    outcome.pose_judged = true;
    outcome.add_s = std::numeric_limits<double>::infinity();
    outcome.add_s_any_model = std::numeric_limits<double>::infinity();
    if (outcome.segmentation.outcome != SegmentOutcome::kFound || !outcome.pose) return;
    const TrueModels::Model& model = models.of(t.model);
    outcome.add_s_any_model = add_s(model.points, t.pose, outcome.pose->cast<double>()) /
                              posed_diameter(model.points, t.pose);
    outcome.pose_correct_any_model = outcome.add_s_any_model < kAddSThreshold;
    if (!outcome.correct || outcome.predicted_model != name) return;
    outcome.add_s = outcome.add_s_any_model;
    outcome.pose_correct = outcome.add_s < kAddSThreshold;
    if (!model.symmetric)
        outcome.rotation_error = rotation_error_degrees(t.pose, outcome.pose->cast<double>());
}

}  // namespace

SceneEvaluationReport evaluate_scenes(const Recognizer& recognizer, const SceneSet& set,
                                      const SceneEvaluationOptions& options) {
    SceneEvaluationReport report;
    report.scene_set = set.path;
    report.grouping =
        options.segmentation.grouping == Grouping::kConvexity ? "convexity" : "euclidean";
    std::map<std::string, SceneTypeSummary> types;
    const std::optional<SceneTruth> truth = read_scene_truth(set.path);
    std::optional<TrueModels> true_models;
    std::set<std::pair<std::string, std::string>> held;  // (class, model name) of the database
    if (truth) {
        report.truth = truth->root;
        true_models.emplace(truth->root);
        for (const ViewLabel& label : recognizer.classifier().labels())
            held.emplace(label.class_name, label.model_name);
    }
    double segment_ms = 0.0, recognize_ms = 0.0;
    std::size_t frames = 0;
    for (std::size_t s = 0; s < set.scenes.size(); ++s) {
        const LabelledScene& scene = set.scenes[s];
        try {
            const PointCloud cloud = read_cloud(scene.file);
            if (cloud.labels.size() != cloud.points.size())
                throw std::invalid_argument("the cloud has no per-point label field");
            auto start = std::chrono::steady_clock::now();
            SegmentationResult segmentation = segment_scene(cloud, options.segmentation);
            const double segmented = milliseconds_since(start);
            start = std::chrono::steady_clock::now();
            const SceneRecognition recognition =
                recognizer.recognize(std::move(segmentation), cloud);
            segment_ms += segmented;
            recognize_ms += milliseconds_since(start);
            ++frames;

            std::vector<Cluster> clusters;
            clusters.reserve(recognition.objects.size());
            for (const RecognizedObject& o : recognition.objects) clusters.push_back(o.cluster);
            const SegmentationScore score = score_segmentation(cloud.points, cloud.labels, clusters,
                                                               options.labels, options.criteria);

            // The summaries this scene counts in: its type's and the overall one.
            std::vector<SceneTypeSummary*> rows = {&types["all"]};
            if (!scene.type.empty()) rows.push_back(&types[scene.type]);
            for (SceneTypeSummary* t : rows) {
                ++t->scenes;
                t->clusters += score.clusters;
                t->background_clusters += score.background_clusters;
                t->shared_clusters += score.shared_clusters;
            }
            for (const ObjectSegmentation& o : score.objects) {
                SceneObjectOutcome outcome;
                outcome.scene = scene.file;
                outcome.type = scene.type;
                outcome.segmentation = o;
                for (const SceneObjectLabel& label : scene.objects)
                    if (label.object_id == o.object_id) outcome.true_class = label.class_name;
                if (o.cluster >= 0) {
                    const RecognizedObject& r =
                        recognition.objects[static_cast<std::size_t>(o.cluster)];
                    if (r.classified()) {
                        outcome.predicted_class = r.classification.class_name;
                        outcome.predicted_model = r.classification.best_model;
                        outcome.pose = r.classification.pose;
                    }
                }
                outcome.correct = o.outcome == SegmentOutcome::kFound &&
                                  !outcome.true_class.empty() &&
                                  outcome.predicted_class == outcome.true_class;
                if (truth) judge_pose(*truth, *true_models, held, outcome);
                for (SceneTypeSummary* t : rows) {
                    ++t->objects;
                    t->found += o.outcome == SegmentOutcome::kFound;
                    t->split += o.outcome == SegmentOutcome::kSplit;
                    t->merged += o.outcome == SegmentOutcome::kMerged;
                    t->missed += o.outcome == SegmentOutcome::kMissed;
                    t->labelled += !outcome.true_class.empty();
                    t->correct += outcome.correct;
                    t->posed += outcome.pose_judged;
                    t->pose_correct += outcome.pose_correct;
                    t->pose_correct_any_model += outcome.pose_correct_any_model;
                    if (outcome.rotation_error)
                        t->rotation_errors.push_back(*outcome.rotation_error);
                }
                report.objects.push_back(std::move(outcome));
            }
        } catch (const std::exception& e) {
            report.failures.push_back({scene.file, e.what()});
        }
        if (options.progress) options.progress(s + 1, set.scenes.size());
    }
    for (auto& [name, summary] : types) {
        summary.type = name;
        if (name != "all") report.types.push_back(summary);
    }
    if (types.count("all")) report.types.push_back(types["all"]);
    report.classes = summarize_classes(report.objects);
    if (frames) {
        report.segment_ms = segment_ms / static_cast<double>(frames);
        report.recognize_ms = recognize_ms / static_cast<double>(frames);
    }
    return report;
}

}  // namespace esf
