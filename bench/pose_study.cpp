// Where verified poses go wrong on generated scenes whose models the database holds (a study;
// BENCHMARKS.md, "Pose"): for each object at least half visible and found as one cluster, the
// rank of its own model among the k-NN neighbours, the score of the fit verification chose, and
// the score of its own model fitted from its nearest view and from its true pose.
//   pose_study DB SCENES.csv   (truth.json beside SCENES.csv; prints one CSV row per object)
#include <Eigen/Core>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

#include "esf/evaluation/pose_accuracy.hpp"
#include "esf/evaluation/scene_evaluation.hpp"
#include "esf/evaluation/scene_truth.hpp"
#include "esf/evaluation/segmentation_evaluation.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/pose_verification.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/segmentation/segmentation.hpp"
#include "esf/training/database.hpp"

namespace fs = std::filesystem;

namespace {

void study(const std::string& db_path, const std::string& scenes_csv) {
    esf::read_scene_set(scenes_csv);  // refuses what is not a scene set
    const std::optional<esf::SceneTruth> truth = esf::read_scene_truth(scenes_csv);
    if (!truth) throw std::runtime_error(scenes_csv + ": no truth.json beside it");
    esf::RecognizerOptions options;
    options.threads = 1;
    const esf::Recognizer recognizer(db_path, options);
    esf::Database db(db_path, esf::OpenMode::kRead);
    std::map<std::string, std::shared_ptr<esf::PreparedModel>> prepared;
    const esf::VerificationOptions& vo = options.verification;
    std::printf(
        "scene,object,class,model,outcome,rank,chosen_class,chosen_model,chosen_score,"
        "own_view_score,own_truth_score,own_view_adds\n");
    // truth.json's objects come by scene file, then object id: each scene is read once.
    std::string scene_file;
    esf::PointCloud cloud;
    esf::SceneRecognition rec;
    esf::SegmentationScore score;
    for (const auto& [key, t] : truth->objects) {
        if (key.first != scene_file) {
            scene_file = key.first;
            cloud = esf::read_cloud((fs::path(scenes_csv).parent_path() / scene_file).string());
            rec = recognizer.recognize(esf::segment_scene(cloud, {}), cloud);
            std::vector<esf::Cluster> clusters;
            for (const auto& o : rec.objects) clusters.push_back(o.cluster);
            score = esf::score_segmentation(cloud.points, cloud.labels, clusters);
        }
        if (t.visible < 0.5) continue;
        const std::uint32_t id = key.second;
        const std::string& cls = t.class_name;
        const std::string model = fs::path(t.model).stem().string();
        const Eigen::Matrix4d& pose = t.pose;
        const esf::ObjectSegmentation* seg_o = nullptr;
        for (const auto& o : score.objects)
            if (o.object_id == id) seg_o = &o;
        if (!seg_o) continue;
        const std::string outcome = esf::to_string(seg_o->outcome);
        std::printf("%s,%u,%s,%s,%s", scene_file.c_str(), id, cls.c_str(), model.c_str(),
                    outcome.c_str());
        if (seg_o->cluster < 0 || !rec.objects[seg_o->cluster].classified()) {
            std::printf(",,,,,,,\n");
            continue;
        }
        const esf::RecognizedObject& r = rec.objects[seg_o->cluster];
        int rank = -1;
        const esf::NeighbourView* own = nullptr;
        // Unverified neighbours.
        const esf::QueryDescriptor d = recognizer.describe(r.cluster.points);
        const esf::Classification knn = recognizer.classify_descriptor(d.signatures);
        for (std::size_t i = 0; i < knn.neighbours.size(); ++i)
            if (knn.neighbours[i].model_name == model && knn.neighbours[i].class_name == cls) {
                rank = static_cast<int>(i);
                own = &knn.neighbours[i];
                break;
            }
        auto& pm = prepared[cls + "/" + model];
        if (!pm) {
            std::optional<esf::ModelSurface> surface = db.model_surface(cls, model);
            if (!surface)
                throw std::runtime_error(db_path + ": no stored surface of " + cls + "/" + model);
            pm = std::make_shared<esf::PreparedModel>(std::move(*surface));
        }
        const esf::PreparedObservation obs(esf::Observation{r.cluster.points, &cloud}, vo.camera);
        const esf::PoseFit at_truth =
            esf::fit_model(*pm, pose, obs, vo, false, esf::FitStart::kCameraPose);
        double view_score = -9, view_adds = -1;
        if (own) {
            const esf::PoseFit f = esf::fit_model(*pm, own->pose.cast<double>(), obs, vo);
            view_score = f.fit.score();
            view_adds = esf::add_s(pm->surface().points, pose, f.model_to_camera) /
                        esf::posed_diameter(pm->surface().points, pose);
        }
        std::printf(",%d,%s,%s,%.3f,%.3f,%.3f,%.3f\n", rank, r.classification.class_name.c_str(),
                    r.classification.best_model.c_str(),
                    r.classification.fit ? r.classification.fit->score() : -9.0, view_score,
                    at_truth.fit.score(), view_adds);
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3) {
        std::cerr << "usage: pose_study DB SCENES.csv\n";
        return 1;
    }
    try {
        study(argv[1], argv[2]);
    } catch (const std::exception& e) {
        std::cerr << "pose_study: error: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
