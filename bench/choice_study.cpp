// What verification's choice among its candidates reads (a study; BENCHMARKS.md, "The choice
// among the candidates"): for each object found as one cluster in a scene set (or each view of
// a test set), every candidate verification fits, with its neighbour's k-NN figures and its fit,
// and the object's true class. One CSV row per object and candidate; a learned rule is then fitted
// and judged offline (bench/choice_rule.py).
//   choice_study DB SCENES.csv|TESTSET.csv [CANDIDATES]   (scene sets have scene_file columns)
#include <Eigen/Core>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>

#include "candidate_fits.hpp"
#include "esf/evaluation/evaluation.hpp"
#include "esf/evaluation/scene_evaluation.hpp"
#include "esf/evaluation/scene_truth.hpp"
#include "esf/evaluation/segmentation_evaluation.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/segmentation/segmentation.hpp"

namespace fs = std::filesystem;

namespace {

void print_candidates(const esf::Recognizer& recognizer, const std::string& scene,
                      std::uint32_t object, const std::string& true_class,
                      const std::string& true_model, const esf::Points& points,
                      const esf::PointCloud* frame) {
    const std::optional<esf::bench::CandidateFits> fitted =
        esf::bench::fit_candidates(recognizer, points, frame);
    if (!fitted) return;
    const esf::Classification& knn = fitted->knn;
    const std::vector<esf::CandidateFit>& candidates = fitted->fits;
    for (std::size_t j = 0; j < candidates.size(); ++j) {
        const esf::CandidateFit& f = candidates[j];
        const esf::NeighbourView& n = knn.neighbours[f.neighbour];
        std::size_t votes = 0;
        for (const esf::NeighbourView& v : knn.neighbours) votes += v.class_name == n.class_name;
        std::printf(
            "%s,%u,%s,%s,%zu,%zu,%zu,%s,%s,%.5f,%.5f,%zu,%.4f,%.4f,%.4f,%.3f,%.4f,%.4f,%d,%d\n",
            scene.c_str(), object, true_class.c_str(), true_model.c_str(), points.size(), j,
            f.neighbour, n.class_name.c_str(), n.model_name.c_str(), n.distance,
            knn.neighbours.front().distance, votes, f.fit.fit.inliers, f.fit.fit.support,
            f.fit.fit.violations, f.fit.fit.rms_mm, f.fit.scale, f.shape_term,
            f.fit.verified ? 1 : 0, n.class_name == knn.class_name ? 1 : 0);
    }
}

void study(const std::string& db_path, const std::string& csv, std::size_t candidates) {
    esf::RecognizerOptions options;
    options.threads = 1;
    options.verification.candidates = candidates;
    const esf::Recognizer recognizer(db_path, options);
    std::printf(
        "scene,object,class,model,points,candidate,neighbour,candidate_class,candidate_model,"
        "distance,nearest_distance,class_votes,inliers,support,violations,rms_mm,scale,"
        "shape_term,verified,knn_class\n");
    bool scenes = false;
    try {
        esf::read_scene_set(csv);
        scenes = true;
    } catch (const std::exception&) {
    }
    if (!scenes) {
        const esf::TestSet test_set = esf::read_test_set(csv);
        std::uint32_t i = 0;
        for (const esf::TestSample& sample : test_set.samples) {
            const esf::FinitePoints cloud =
                esf::drop_non_finite(esf::read_cloud(sample.file).points);
            print_candidates(recognizer, fs::path(sample.file).filename().string(), i++,
                             sample.class_name, "", cloud.points, nullptr);
        }
        return;
    }
    const esf::SceneSet set = esf::read_scene_set(csv);
    const std::optional<esf::SceneTruth> truth = esf::read_scene_truth(csv);
    // The recognizer of the study fits more candidates; the scenes are segmented and their
    // parts merged as by default.
    esf::RecognizerOptions pipeline_options;
    pipeline_options.threads = 1;
    const esf::Recognizer pipeline(db_path, pipeline_options);
    for (const esf::LabelledScene& scene : set.scenes) {
        const esf::PointCloud cloud = esf::read_cloud(scene.file);
        const esf::SceneRecognition rec = pipeline.recognize(esf::segment_scene(cloud, {}), cloud);
        std::optional<esf::PointCloud> image;  // the frame verification reads
        const esf::PointCloud* frame =
            esf::verification_frame(cloud, options.verification.camera, image);
        std::vector<esf::Cluster> clusters;
        for (const auto& o : rec.objects) clusters.push_back(o.cluster);
        const esf::SegmentationScore score =
            esf::score_segmentation(cloud.points, cloud.labels, clusters);
        const std::string name = fs::path(scene.file).filename().string();
        for (const esf::SceneObjectLabel& label : scene.objects) {
            const esf::ObjectSegmentation* seg = nullptr;
            for (const auto& o : score.objects)
                if (o.object_id == label.object_id) seg = &o;
            if (!seg || seg->outcome != esf::SegmentOutcome::kFound || seg->cluster < 0) continue;
            std::string model;
            if (truth) {
                const auto it = truth->objects.find({name, label.object_id});
                if (it != truth->objects.end()) model = fs::path(it->second.model).stem().string();
            }
            print_candidates(recognizer, name, label.object_id, label.class_name, model,
                             rec.objects[static_cast<std::size_t>(seg->cluster)].cluster.points,
                             frame);
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3 && argc != 4) {
        std::cerr << "usage: choice_study DB SCENES.csv|TESTSET.csv [CANDIDATES]\n";
        return 1;
    }
    try {
        study(argv[1], argv[2], argc == 4 ? std::stoul(argv[3]) : 3);
    } catch (const std::exception& e) {
        std::cerr << "choice_study: error: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
