// How far a real view's points lie from the model verification fitted (a study; BENCHMARKS.md,
// "Tried and not kept: free proportions"): for each view of CLASS in a test set that is named
// CLASS, the share of its points within 4, 8, 15, 30 and 60 mm of the fitted model's
// camera-facing surface samples, and the same over all those views.
//   residual_study DB TESTSET.csv CLASS   (one line per view, then "all")
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>

#include "esf/evaluation/evaluation.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/recognizer.hpp"

namespace {

constexpr std::array<double, 5> kEdges = {4.0, 8.0, 15.0, 30.0, 60.0};  // mm
using Shares = std::array<double, kEdges.size() + 1>;

void print(const std::string& name, const Shares& counts, double points, const std::string& tail) {
    std::printf("%s", name.c_str());
    const char* labels[] = {"<4", "4-8", "8-15", "15-30", "30-60", ">60"};
    for (std::size_t k = 0; k < counts.size(); ++k)
        std::printf(" %s %.2f", labels[k], counts[k] / points);
    std::printf("%s\n", tail.c_str());
}

void study(const std::string& db, const std::string& csv, const std::string& wanted) {
    const esf::TestSet test_set = esf::read_test_set(csv);
    esf::RecognizerOptions options;
    options.threads = 1;
    const esf::Recognizer recognizer(db, options);
    Shares all{};
    double all_points = 0.0;
    for (const esf::TestSample& sample : test_set.samples) {
        if (sample.class_name != wanted) continue;
        const esf::FinitePoints cloud = esf::drop_non_finite(esf::read_cloud(sample.file).points);
        const esf::Classification c = recognizer.classify(cloud.points);
        if (c.class_name != wanted || !c.fit) continue;
        const esf::Points posed = recognizer.posed_surface(c);
        Shares counts{};
        for (const Eigen::Vector3f& q : cloud.points) {
            float best = std::numeric_limits<float>::max();
            for (const Eigen::Vector3f& p : posed) best = std::min(best, (p - q).squaredNorm());
            const double mm = 1000.0 * std::sqrt(static_cast<double>(best));
            const auto k = static_cast<std::size_t>(
                std::upper_bound(kEdges.begin(), kEdges.end(), mm) - kEdges.begin());
            counts[k] += 1.0;
        }
        const auto n = static_cast<double>(cloud.points.size());
        for (std::size_t k = 0; k < counts.size(); ++k) all[k] += counts[k];
        all_points += n;
        print(std::filesystem::path(sample.file).filename().string(), counts, n,
              " model " + c.best_model);
    }
    if (all_points > 0.0) print("all", all, all_points, "");
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 4) {
        std::cerr << "usage: residual_study DB TESTSET.csv CLASS\n";
        return 1;
    }
    try {
        study(argv[1], argv[2], argv[3]);
    } catch (const std::exception& e) {
        std::cerr << "residual_study: error: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
