// Weight learning: on views whose first block is pure noise, its weight goes down and the
// leave-one-model-out objective goes up; the objective never decreases; results do not depend
// on the thread count; bad options are refused by message.

#include "esf/evaluation/weight_learning.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "esf/evaluation/evaluation.hpp"
#include "esf/recognition/knn_index.hpp"

namespace {

/// prefix + i (GCC 12 warns falsely, -Wrestrict, about "literal" + std::to_string()).
std::string numbered(const char* prefix, int i) {
    std::string s(prefix);
    s += std::to_string(i);
    return s;
}

constexpr int kBlocks = 10, kBins = 8;

/// 4 classes x 5 models x 6 views, 10 blocks of 8 bins. Blocks 1..9: a class prototype plus
/// model and view noise; block 0: noise much larger than the class differences.
esf::DescriptorMatrix noisy_block_matrix(std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::normal_distribution<float> n(0.0f, 1.0f);
    const int classes = 4, models = 5, views = 6, dim = kBlocks * kBins;
    std::vector<std::vector<float>> prototype(classes, std::vector<float>(dim));
    for (auto& p : prototype)
        for (float& v : p) v = u(rng);
    esf::DescriptorMatrix m;
    m.kind = {"esf-like", 1, dim};
    for (int c = 0; c < classes; ++c) {
        m.categories.push_back(numbered("c", c));
        for (int i = 0; i < models; ++i) {
            esf::ModelInfo info;
            info.category = m.categories.back();
            info.name = numbered("m", i);
            const auto model = static_cast<std::uint32_t>(m.models.size());
            m.models.push_back(info);
            std::vector<float> shape(dim);
            for (int d = 0; d < dim; ++d) shape[static_cast<std::size_t>(d)] = 0.25f * n(rng);
            for (int v = 0; v < views; ++v) {
                esf::DescriptorRow row;
                row.category = static_cast<std::uint32_t>(c);
                row.model = model;
                row.view_index = v;
                m.row_info.push_back(row);
                for (int d = 0; d < dim; ++d) {
                    const auto s = static_cast<std::size_t>(d);
                    const float value = d < kBins ? 20.0f * u(rng)
                                                  : prototype[static_cast<std::size_t>(c)][s] +
                                                        shape[s] + 0.1f * n(rng);
                    m.data.push_back(std::max(0.0f, value));
                }
            }
        }
    }
    return m;
}

esf::WeightLearningOptions small_options() {
    esf::WeightLearningOptions options;
    options.blocks.assign(kBlocks, kBins);
    options.max_queries = 0;
    options.candidates = 10;
    options.threads = 1;
    return options;
}

TEST(LearnWeights, BlocksMayDifferInSize) {
    // The noise block split in two halves of 4 bins, then nine blocks of 8: both halves lose
    // weight against the informative blocks (whose median holds; single ones drift).
    const esf::DescriptorMatrix m = noisy_block_matrix(1);
    esf::WeightLearningOptions options = small_options();
    options.blocks = {kBins / 2, kBins / 2};
    options.blocks.insert(options.blocks.end(), kBlocks - 1, kBins);
    const esf::WeightLearningResult r = esf::learn_weights(m, options);
    ASSERT_EQ(r.weights.size(), options.blocks.size());
    std::vector<float> others(r.weights.begin() + 2, r.weights.end());
    std::nth_element(others.begin(), others.begin() + 4, others.end());
    std::string all;
    for (const float w : r.weights) all += std::to_string(w) + " ";
    EXPECT_LT(std::max(r.weights[0], r.weights[1]), others[4]) << "weights " << all;
    EXPECT_LT(r.weights[0] + r.weights[1], others[4]) << "weights " << all;
    EXPECT_GT(r.objective_after, r.objective_before);
}

TEST(LearnWeights, TheNoiseBlockLosesWeight) {
    const esf::DescriptorMatrix m = noisy_block_matrix(1);
    std::vector<double> progress;
    esf::WeightLearningOptions options = small_options();
    options.progress = [&](int, double objective) { progress.push_back(objective); };
    const esf::WeightLearningResult r = esf::learn_weights(m, options);
    ASSERT_EQ(r.weights.size(), static_cast<std::size_t>(kBlocks));
    EXPECT_EQ(r.queries, m.rows());
    double mean = 0.0;
    for (const float w : r.weights) mean += w / kBlocks;
    EXPECT_NEAR(mean, 1.0, 1e-5);
    // The informative blocks are interchangeable, so single ones may drift; their median holds.
    std::vector<float> others(r.weights.begin() + 1, r.weights.end());
    std::nth_element(others.begin(), others.begin() + 4, others.end());
    std::string all;
    for (const float w : r.weights) all += std::to_string(w) + " ";
    EXPECT_LT(r.weights[0], 0.5f * others[4]) << "weights " << all;
    EXPECT_GT(r.objective_after, r.objective_before);
    EXPECT_GE(r.top1_after, r.top1_before);
    EXPECT_GT(r.accepted, 0);
    EXPECT_EQ(progress, r.history);

    // The learned weights really improve leave-one-model-out 1-NN.
    esf::SyntheticOptions plain;
    plain.k = 1;
    esf::SyntheticOptions weighted = plain;
    weighted.weights = esf::expand_block_weights(r.weights, kBins);
    EXPECT_GT(esf::evaluate_synthetic(m, weighted).top1, esf::evaluate_synthetic(m, plain).top1);
    EXPECT_DOUBLE_EQ(esf::evaluate_synthetic(m, weighted).top1, r.top1_after);
}

TEST(LearnWeights, TheObjectiveNeverDecreases) {
    for (const std::uint64_t seed : {2u, 3u}) {
        const esf::DescriptorMatrix m = noisy_block_matrix(seed);
        esf::WeightLearningOptions options = small_options();
        options.max_queries = 50;
        options.smooth = 0.2;
        const esf::WeightLearningResult r = esf::learn_weights(m, options);
        EXPECT_EQ(r.queries, 50u);
        double previous = r.objective_before;
        for (const double v : r.history) {
            EXPECT_GE(v, previous);
            previous = v;
        }
        EXPECT_EQ(r.objective_after, previous);
        EXPECT_LE(r.iterations, options.max_iterations);
    }
}

TEST(LearnWeights, IsDeterministicForAnyThreadCount) {
    const esf::DescriptorMatrix m = noisy_block_matrix(4);
    esf::WeightLearningOptions options = small_options();
    const esf::WeightLearningResult one = esf::learn_weights(m, options);
    options.threads = 3;
    const esf::WeightLearningResult three = esf::learn_weights(m, options);
    EXPECT_EQ(one.weights, three.weights);
    EXPECT_EQ(one.history, three.history);
    EXPECT_EQ(one.iterations, three.iterations);
}

TEST(LearnWeights, GroupsAndInitialWeightsAreUsed) {
    const esf::DescriptorMatrix m = noisy_block_matrix(5);
    esf::WeightLearningOptions options = small_options();
    options.max_iterations = 0;
    options.initial = std::vector<float>(kBlocks, 2.0f);  // rescaled to mean 1
    const esf::WeightLearningResult r = esf::learn_weights(m, options);
    EXPECT_EQ(r.weights, std::vector<float>(kBlocks, 1.0f));
    EXPECT_EQ(r.objective_after, r.objective_before);
    EXPECT_TRUE(r.history.empty());
    options.groups.assign(m.models.size(), "g");
    options.groups[0] = "h";
    EXPECT_NO_THROW(esf::learn_weights(m, options));
}

TEST(LearnWeights, WithoutTheMarginTheObjectiveIsTheAccuracy) {
    esf::DescriptorMatrix m = noisy_block_matrix(7);
    esf::WeightLearningOptions options = small_options();
    options.smooth = 0.0;
    options.class_balanced = false;
    const esf::WeightLearningResult r = esf::learn_weights(m, options);
    EXPECT_NEAR(r.objective_before, r.top1_before, 1e-12);
    EXPECT_NEAR(r.objective_after, r.top1_after, 1e-12);
    // Class-balanced: the mean of the class accuracies (evaluate_synthetic's class_top1).
    m.row_info.resize(m.rows() - 20);  // the last class loses 20 of its 30 views
    m.data.resize(m.rows() * 80);
    options.class_balanced = true;
    options.max_queries = 0;
    options.max_iterations = 0;
    esf::SyntheticOptions plain;
    plain.k = 1;
    const esf::EvaluationReport report = esf::evaluate_synthetic(m, plain);
    EXPECT_NE(report.class_top1, report.top1);
    EXPECT_NEAR(esf::learn_weights(m, options).objective_before, report.class_top1, 1e-12);
}

TEST(LearnWeights, RejectsBadInput) {
    const esf::DescriptorMatrix m = noisy_block_matrix(6);
    auto message = [&](const esf::DescriptorMatrix& matrix, const esf::WeightLearningOptions& o) {
        try {
            esf::learn_weights(matrix, o);
        } catch (const std::invalid_argument& e) {
            return std::string(e.what());
        }
        return std::string("(no exception)");
    };
    esf::WeightLearningOptions options = small_options();
    options.blocks.assign(7, kBins);
    EXPECT_EQ(message(m, options), "learn_weights: blocks of 56 bins in all for dimension 80");
    options.blocks = {kBins * kBlocks, 0};
    EXPECT_EQ(message(m, options), "learn_weights: a block of size 0");
    options = small_options();
    options.candidates = 1;
    EXPECT_EQ(message(m, options), "learn_weights: candidates must be >= 2, got 1");
    options = small_options();
    options.initial = {1.0f};
    EXPECT_EQ(message(m, options), "learn_weights: 1 initial weights for 10 blocks");
    options = small_options();
    esf::DescriptorMatrix multi = m;
    multi.row_info[1].view_index = 0;  // rows 0 and 1: two signatures of one view
    multi.row_info[1].signature = 1;
    EXPECT_EQ(message(multi, options),
              "learn_weights: esf-like views have several signatures; block weights need one");
}

}  // namespace
