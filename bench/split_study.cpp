// Why split objects stay split (a study; BENCHMARKS.md, "Parts apart by a gap"): for each object
// of a generated scene set that comes out in several clusters after recognition (parts merged as
// by default), its two largest parts are fitted as one, as merging parts fits a pair, and the
// row says how far apart they are, what each part was named and scored, and what the pair's fit
// would be. Objects less than half visible are left out.
//   split_study DB SCENES.csv   (truth.json beside SCENES.csv for the models; one CSV row each)
#include <Eigen/Core>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "esf/evaluation/scene_evaluation.hpp"
#include "esf/evaluation/scene_truth.hpp"
#include "esf/evaluation/segmentation_evaluation.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/segmentation/segmentation.hpp"

namespace fs = std::filesystem;

namespace {

double score_of(const esf::RecognizedObject& o) {
    return o.classification.fit ? o.classification.fit->score() : -9.0;
}

double gap_between(const esf::Points& a, const esf::Points& b) {
    float best = std::numeric_limits<float>::max();
    for (std::size_t i = 0; i < a.size(); i += 3)
        for (std::size_t j = 0; j < b.size(); j += 3)
            best = std::min(best, (a[i] - b[j]).squaredNorm());
    return std::sqrt(static_cast<double>(best));
}

void study(const std::string& db_path, const std::string& csv) {
    esf::RecognizerOptions options;
    options.threads = 1;
    const esf::Recognizer recognizer(db_path, options);
    const esf::SceneSet set = esf::read_scene_set(csv);
    const std::optional<esf::SceneTruth> truth = esf::read_scene_truth(csv);
    const esf::LabelScheme scheme;
    std::printf(
        "scene,object,class,model,parts,points_a,points_b,gap_cm,class_a,score_a,class_b,score_b,"
        "pair_class,pair_model,pair_verified,pair_inliers,pair_score,gain\n");
    for (const esf::LabelledScene& scene : set.scenes) {
        const esf::PointCloud cloud = esf::read_cloud(scene.file);
        const esf::SceneRecognition r = recognizer.recognize(esf::segment_scene(cloud, {}), cloud);
        std::vector<esf::Cluster> clusters;
        for (const auto& o : r.objects) clusters.push_back(o.cluster);
        const esf::SegmentationScore score =
            esf::score_segmentation(cloud.points, cloud.labels, clusters, scheme);
        std::optional<esf::PointCloud> image;  // the frame verification reads
        const esf::PointCloud* frame =
            esf::verification_frame(cloud, options.verification.camera, image);
        const std::string name = fs::path(scene.file).filename().string();
        for (const esf::SceneObjectLabel& label : scene.objects) {
            const esf::ObjectSegmentation* seg = nullptr;
            for (const auto& o : score.objects)
                if (o.object_id == label.object_id) seg = &o;
            if (!seg || seg->outcome != esf::SegmentOutcome::kSplit) continue;
            std::string model;
            if (truth) {
                const auto it = truth->objects.find({name, label.object_id});
                if (it != truth->objects.end()) {
                    if (it->second.visible < 0.5) continue;
                    model = fs::path(it->second.model).stem().string();
                }
            }
            // The clusters holding its points, most first.
            std::vector<std::pair<std::size_t, std::size_t>> held;  // (points, cluster)
            for (std::size_t c = 0; c < clusters.size(); ++c) {
                std::size_t n = 0;
                for (const std::size_t i : clusters[c].indices)
                    n += cloud.labels[i] / scheme.divisor == label.object_id;
                if (n) held.emplace_back(n, c);
            }
            if (held.size() < 2) continue;
            std::sort(held.rbegin(), held.rend());
            const esf::RecognizedObject& a = r.objects[held[0].second];
            const esf::RecognizedObject& b = r.objects[held[1].second];
            esf::RecognizedObject pair;
            pair.cluster = esf::merge_clusters(a.cluster, b.cluster, r.plane);
            const esf::QueryDescriptor d = recognizer.describe(pair.cluster.points);
            if (!d.ok()) continue;
            pair.classification = recognizer.classify_descriptor(d.signatures);
            recognizer.verify(pair.classification, esf::Observation{pair.cluster.points, frame});
            const auto na = static_cast<double>(a.cluster.points.size());
            const auto nb = static_cast<double>(b.cluster.points.size());
            const double pair_score = score_of(pair);
            std::printf("%s,%u,%s,%s,%zu,%zu,%zu,%.1f,%s,%.2f,%s,%.2f,%s,%s,%d,%.2f,%.2f,%.2f\n",
                        name.c_str(), label.object_id, label.class_name.c_str(), model.c_str(),
                        held.size(), held[0].first, held[1].first,
                        100.0 * gap_between(a.cluster.points, b.cluster.points),
                        a.classification.class_name.c_str(), score_of(a),
                        b.classification.class_name.c_str(), score_of(b),
                        pair.classification.class_name.c_str(),
                        pair.classification.best_model.c_str(),
                        pair.classification.verified ? 1 : 0,
                        pair.classification.fit ? pair.classification.fit->inliers : -1.0,
                        pair_score, pair_score - (na * score_of(a) + nb * score_of(b)) / (na + nb));
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3) {
        std::cerr << "usage: split_study DB SCENES.csv\n";
        return 1;
    }
    try {
        study(argv[1], argv[2]);
    } catch (const std::exception& e) {
        std::cerr << "split_study: error: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
