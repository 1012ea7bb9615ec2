// What verification could choose from (a study; BENCHMARKS.md, "Why real cans are named box"):
// for each labelled view of a test set, every distinct model among its k-NN neighbours is fitted
// to the view's points as verification fits a candidate (from the neighbour's view, a free scale
// where the database rescaled the model), and its fit printed, nearest first. Shows whether the
// true class has a model that fits at all, and what fits better.
//   candidate_study DB TESTSET.csv [CLASS]   (only the views of CLASS when given)
// Prints one CSV row per view and candidate.
#include <Eigen/Core>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "esf/evaluation/evaluation.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/pose_verification.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/training/database.hpp"

namespace fs = std::filesystem;

namespace {

void study(const std::string& db_path, const std::string& csv, const std::string& only) {
    const esf::TestSet test_set = esf::read_test_set(csv);
    esf::RecognizerOptions options;
    options.threads = 1;
    const esf::Recognizer recognizer(db_path, options);
    const esf::Database db(db_path, esf::OpenMode::kRead);
    std::map<std::string, double> scales;  // category/name -> the database's scale
    for (const esf::ModelInfo& m : db.models()) scales[m.category + "/" + m.name] = m.scale;
    std::map<std::string, std::shared_ptr<esf::PreparedModel>> prepared;
    const esf::VerificationOptions& vo = options.verification;
    std::printf(
        "file,class,rank,candidate_class,candidate_model,distance,score,inliers,support,"
        "violations,rms_mm,scale,verified\n");
    for (const esf::TestSample& sample : test_set.samples) {
        if (!only.empty() && sample.class_name != only) continue;
        const esf::FinitePoints cloud = esf::drop_non_finite(esf::read_cloud(sample.file).points);
        const esf::QueryDescriptor d = recognizer.describe(cloud.points);
        const esf::Classification knn = recognizer.classify_descriptor(d.signatures);
        const esf::PreparedObservation observation(esf::Observation{cloud.points, nullptr},
                                                   vo.camera);
        std::vector<std::string> fitted;
        for (std::size_t i = 0; i < knn.neighbours.size(); ++i) {
            const esf::NeighbourView& n = knn.neighbours[i];
            const std::string key = n.class_name + "/" + n.model_name;
            if (std::find(fitted.begin(), fitted.end(), key) != fitted.end()) continue;
            fitted.push_back(key);
            std::shared_ptr<esf::PreparedModel>& model = prepared[key];
            if (!model) {
                std::optional<esf::ModelSurface> surface =
                    db.model_surface(n.class_name, n.model_name);
                if (!surface) throw std::runtime_error(db_path + ": no stored surface of " + key);
                model = std::make_shared<esf::PreparedModel>(std::move(*surface));
            }
            const esf::PoseFit fit =
                esf::fit_model(*model, n.pose.cast<double>(), observation, vo, scales[key] != 1.0);
            std::printf("%s,%s,%zu,%s,%s,%.4f,%.3f,%.3f,%.3f,%.3f,%.2f,%.3f,%d\n",
                        fs::path(sample.file).filename().c_str(), sample.class_name.c_str(), i,
                        n.class_name.c_str(), n.model_name.c_str(), n.distance, fit.fit.score(),
                        fit.fit.inliers, fit.fit.support, fit.fit.violations, fit.fit.rms_mm,
                        fit.scale, fit.verified ? 1 : 0);
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3 && argc != 4) {
        std::cerr << "usage: candidate_study DB TESTSET.csv [CLASS]\n";
        return 1;
    }
    try {
        study(argv[1], argv[2], argc == 4 ? argv[3] : "");
    } catch (const std::exception& e) {
        std::cerr << "candidate_study: error: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
