// Evaluation: hand-computed metrics on made-up outcomes, the test-set CSV reader and its errors,
// leave-one-model-out / leave-one-group-out search against a brute-force oracle, and
// evaluate_test_set on a two-class database.

#include "esf/evaluation/evaluation.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "esf/core/error.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/knn_index.hpp"
#include "evaluation/lomo_search.hpp"
#include "support/error_of.hpp"
#include "support/one_view_database.hpp"

namespace fs = std::filesystem;

namespace {

/// prefix + i (GCC 12 warns falsely, -Wrestrict, about "literal" + std::to_string()).
std::string numbered(const char* prefix, int i) {
    std::string s(prefix);
    s += std::to_string(i);
    return s;
}

using esf::EvaluationReport;
using esf::QueryOutcome;

QueryOutcome outcome(const std::string& file, const std::string& true_class,
                     const std::vector<std::string>& neighbours) {
    QueryOutcome o;
    o.file = file;
    o.true_class = true_class;
    for (std::size_t i = 0; i < neighbours.size(); ++i)
        o.neighbours.push_back({neighbours[i], 0.1 * static_cast<double>(i + 1)});
    return o;
}

using esf::test::error_of;

// ---- metrics --------------------------------------------------------------------------------

TEST(Evaluate, HandComputedMetrics) {
    const std::vector<std::string> classes = {"a", "b", "c"};
    std::vector<QueryOutcome> outcomes = {
        outcome("q1", "a", {"a", "b"}),       // rank 1
        outcome("q2", "a", {"b", "a", "c"}),  // rank 2, 1-NN b
        outcome("q3", "a", {"c", "c", "b"}),  // rank 0 (beyond k = 3), 1-NN c
        outcome("q4", "b", {"b"}),            // rank 1
        outcome("q5", "b", {"a", "a", "b"}),  // rank 3, 1-NN a
        outcome("q6", "z", {"a"}),            // class not in the database: skipped
        outcome("q7", "c", {}),               // failed
        outcome("q8", "z", {}),               // skipped, even though failed
    };
    outcomes[6].error = "c: too few points";
    outcomes[7].error = "unreadable";
    const EvaluationReport r = esf::evaluate(outcomes, 3, classes);

    EXPECT_EQ(r.k, 3u);
    EXPECT_EQ(r.samples, 5u);
    EXPECT_EQ(r.top1_hits, 2u);  // q1, q4
    EXPECT_EQ(r.topk_hits, 4u);  // q1, q2, q4, q5
    EXPECT_DOUBLE_EQ(r.top1, 0.4);
    EXPECT_DOUBLE_EQ(r.topk, 0.8);
    ASSERT_EQ(r.rank_curve.size(), 3u);
    EXPECT_DOUBLE_EQ(r.rank_curve[0], 2.0 / 5.0);
    EXPECT_DOUBLE_EQ(r.rank_curve[1], 3.0 / 5.0);
    EXPECT_DOUBLE_EQ(r.rank_curve[2], 4.0 / 5.0);

    ASSERT_EQ(r.classes.size(), 3u);  // c has only a failed query, but it is listed
    const esf::ClassMetrics& a = r.classes[0];
    EXPECT_EQ(a.class_name, "a");
    EXPECT_EQ(a.samples, 3u);
    EXPECT_DOUBLE_EQ(a.top1, 1.0 / 3.0);
    EXPECT_DOUBLE_EQ(a.topk, 2.0 / 3.0);
    EXPECT_EQ(a.confused_with, "b");  // b and c once each: the first name wins
    EXPECT_EQ(a.confused_count, 1u);
    EXPECT_EQ(a.rank_curve, (std::vector<double>{1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0}));
    const esf::ClassMetrics& b = r.classes[1];
    EXPECT_EQ(b.samples, 2u);
    EXPECT_DOUBLE_EQ(b.top1, 0.5);
    EXPECT_DOUBLE_EQ(b.topk, 1.0);
    EXPECT_EQ(b.confused_with, "a");
    EXPECT_EQ(b.rank_curve, (std::vector<double>{0.5, 0.5, 1.0}));
    const esf::ClassMetrics& c = r.classes[2];
    EXPECT_EQ(c.samples, 0u);
    EXPECT_EQ(c.failed, 1u);
    EXPECT_EQ(c.confused_with, "");

    // Means over the classes with samples (a and b).
    EXPECT_DOUBLE_EQ(r.class_top1, (1.0 / 3.0 + 0.5) / 2.0);
    EXPECT_DOUBLE_EQ(r.class_topk, (2.0 / 3.0 + 1.0) / 2.0);
    EXPECT_DOUBLE_EQ(r.class_rank_curve[1], (2.0 / 3.0 + 0.5) / 2.0);

    EXPECT_EQ(r.confusion_rows, classes);
    EXPECT_EQ(r.confusion_columns, classes);
    const std::vector<std::size_t> expected = {1, 1, 1,   // a -> a (q1), b (q2), c (q3)
                                               1, 1, 0,   // b -> a (q5), b (q4)
                                               0, 0, 0};  // c: failed only
    EXPECT_EQ(r.confusion, expected);

    EXPECT_EQ(r.skipped, 2u);
    ASSERT_EQ(r.missing_classes.size(), 1u);
    EXPECT_EQ(r.missing_classes[0].class_name, "z");
    EXPECT_EQ(r.missing_classes[0].samples, 2u);
    EXPECT_EQ(r.failed, 1u);
    ASSERT_EQ(r.failures.size(), 1u);
    EXPECT_EQ(r.failures[0].file, "q7");
    EXPECT_EQ(r.failures[0].error, "c: too few points");

    ASSERT_EQ(r.queries.size(), 5u);
    EXPECT_EQ(r.queries[1].file, "q2");
    EXPECT_EQ(r.queries[1].predicted, "b");
    EXPECT_EQ(r.queries[1].rank, 2u);
    EXPECT_EQ(r.queries[2].rank, 0u);
    EXPECT_DOUBLE_EQ(r.queries[2].distance, 0.1);
}

TEST(Evaluate, KOneMakesTopKTheNearestView) {
    const std::vector<std::string> classes = {"a", "b"};
    const std::vector<QueryOutcome> outcomes = {outcome("q1", "a", {"b", "a"}),
                                                outcome("q2", "b", {"b", "a"})};
    const EvaluationReport r = esf::evaluate(outcomes, 1, classes);
    EXPECT_DOUBLE_EQ(r.top1, 0.5);
    EXPECT_DOUBLE_EQ(r.topk, 0.5);
    EXPECT_EQ(r.rank_curve.size(), 1u);
    // With k = 2 the first query finds its class at rank 2.
    EXPECT_DOUBLE_EQ(esf::evaluate(outcomes, 2, classes).topk, 1.0);
}

TEST(Evaluate, APredictedClassOutsideTheListAddsAColumn) {
    const std::vector<std::string> classes = {"b", "a"};
    const std::vector<QueryOutcome> outcomes = {outcome("q1", "a", {"x", "a"})};
    const EvaluationReport r = esf::evaluate(outcomes, 2, classes);
    EXPECT_EQ(r.confusion_columns, (std::vector<std::string>{"b", "a", "x"}));
    EXPECT_EQ(r.confusion_rows, (std::vector<std::string>{"a"}));
    EXPECT_EQ(r.confusion_at(0, 2), 1u);
    EXPECT_EQ(r.classes[0].confused_with, "x");
}

TEST(Evaluate, EmptyInputGivesZeros) {
    const std::vector<std::string> classes = {"a"};
    const EvaluationReport r = esf::evaluate(std::vector<QueryOutcome>{}, 10, classes);
    EXPECT_EQ(r.samples, 0u);
    EXPECT_EQ(r.top1, 0.0);
    EXPECT_EQ(r.class_topk, 0.0);
    EXPECT_EQ(r.rank_curve.size(), 10u);
    EXPECT_TRUE(r.classes.empty());
}

TEST(Evaluate, RejectsBadArguments) {
    const std::vector<std::string> classes = {"a", "a"};
    const std::vector<std::string> good = {"a"};
    const std::vector<QueryOutcome> none;
    EXPECT_EQ(error_of([&] { esf::evaluate(none, 0, good); }), "evaluate: k must be >= 1");
    EXPECT_EQ(error_of([&] { esf::evaluate(none, 1, classes); }),
              "evaluate: class 'a' given twice");
    const std::vector<QueryOutcome> empty = {outcome("q", "a", {})};
    EXPECT_EQ(error_of([&] { esf::evaluate(empty, 1, good); }),
              "evaluate: query 0 (q) has neither neighbours nor an error");
}

// ---- test set CSV ---------------------------------------------------------------------------

esf::TestSet parse(const std::string& text, const std::string& path = "sets/t.csv") {
    std::istringstream in(text);
    return esf::read_test_set(in, path);
}

TEST(ReadTestSet, ReadsQuotedFieldsAndResolvesPaths) {
    const esf::TestSet set = parse(
        "id, Class ,file,note\r\n"
        "1,mug,objects/a.pcd,plain\r\n"
        "\r\n"
        "2,\"box\",\"objects/b, c.pcd\",\"a \"\"quoted\"\" note\nover two lines\"\n"
        "3,can,/abs/c.pcd,\n");
    EXPECT_EQ(set.path, "sets/t.csv");
    ASSERT_EQ(set.samples.size(), 3u);
    EXPECT_EQ(set.samples[0].file, "sets/objects/a.pcd");
    EXPECT_EQ(set.samples[0].class_name, "mug");
    EXPECT_EQ(set.samples[0].line, 2u);
    EXPECT_EQ(set.samples[1].file, "sets/objects/b, c.pcd");
    EXPECT_EQ(set.samples[1].class_name, "box");
    EXPECT_EQ(set.samples[1].line, 4u);
    EXPECT_EQ(set.samples[2].file, "/abs/c.pcd");  // absolute paths are kept
    EXPECT_EQ(set.samples[2].line, 6u);            // the quoted note spans lines 4 and 5
    // Without a folder in the CSV path, files stay relative.
    EXPECT_EQ(parse("file,class\nx.pcd,mug\n", "t.csv").samples[0].file, "x.pcd");
}

TEST(ReadTestSet, ErrorsNameTheFileAndLine) {
    auto message = [](const std::string& text) { return error_of([&] { parse(text, "t.csv"); }); };
    EXPECT_EQ(message(""), "t.csv: empty file (expected a header with file and class)");
    EXPECT_EQ(message("file,label\nx.pcd,mug\n"), "t.csv:1: the header has no 'class' column");
    EXPECT_EQ(message("name,class\n"), "t.csv:1: the header has no 'file' column");
    EXPECT_EQ(message("file,class\nx.pcd,mug\ny.pcd\n"),
              "t.csv:3: 1 fields, the header needs at least 2");
    EXPECT_EQ(message("file,class\n\"x.pcd,mug\n"), "t.csv:2: unterminated quoted field");
    EXPECT_EQ(message("file,class\n\"x\"y.pcd,mug\n"),
              "t.csv:2: text after the closing quote of a field");
    EXPECT_EQ(message("file,class\nx.pcd, \n"), "t.csv:2: empty class for x.pcd");
    EXPECT_EQ(message("file,class\n,mug\n"), "t.csv:2: empty file");
    const std::string missing = "/nonexistent/t.csv";
    EXPECT_EQ(error_of([&] { esf::read_test_set(missing); }), missing + ": cannot open test set");
    EXPECT_THROW(esf::read_test_set(missing), esf::IoError);
}

// ---- synthetic: leave one model / group out -------------------------------------------------

/// `categories` x `models` models of `views` views; view v of a model has 1 + (v % signatures)
/// signatures of `dim` random floats.
esf::DescriptorMatrix random_matrix(int categories, int models, int views, int dim, int signatures,
                                    std::uint64_t seed) {
    esf::DescriptorMatrix m;
    m.kind = {"test", 1, dim};
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int c = 0; c < categories; ++c) {
        m.categories.push_back(numbered("c", c));
        for (int i = 0; i < models; ++i) {
            esf::ModelInfo info;
            info.category = m.categories.back();
            info.name = numbered("m", i);
            info.file.append(info.category).append("/").append(info.name).append(".ply");
            info.views = static_cast<std::size_t>(views);
            const auto model = static_cast<std::uint32_t>(m.models.size());
            m.models.push_back(info);
            for (int v = 0; v < views; ++v)
                for (int s = 0; s < 1 + v % signatures; ++s) {
                    esf::DescriptorRow row;
                    row.category = static_cast<std::uint32_t>(c);
                    row.model = model;
                    row.view_index = v;
                    row.signature = s;
                    m.row_info.push_back(row);
                    // Class-dependent offset, so that the class is learnable but not trivial.
                    for (int d = 0; d < dim; ++d)
                        m.data.push_back(u(rng) + (d % categories == c ? 0.3f : 0.0f));
                }
        }
    }
    return m;
}

struct OracleNeighbour {
    std::size_t view;
    double distance;
};

/// Brute force: the k nearest views of view `query` outside its group, by (distance, view);
/// with `per_model` only the first of each model's views in that order.
std::vector<OracleNeighbour> oracle(const esf::DescriptorMatrix& m,
                                    const esf::detail::LomoSetup& setup, std::size_t query,
                                    std::size_t k, const std::vector<float>& weights,
                                    bool per_model) {
    const auto dim = static_cast<std::size_t>(m.kind.dimension);
    std::vector<OracleNeighbour> all;
    for (std::size_t v = 0; v < setup.views(); ++v) {
        if (setup.view_group[v] == setup.view_group[query]) continue;
        double best = INFINITY;
        for (std::size_t a = setup.view_first_row[query]; a < setup.view_first_row[query + 1]; ++a)
            for (std::size_t b = setup.view_first_row[v]; b < setup.view_first_row[v + 1]; ++b) {
                double d = 0.0;
                for (std::size_t i = 0; i < dim; ++i)
                    d += (weights.empty() ? 1.0 : static_cast<double>(weights[i])) *
                         std::abs(static_cast<double>(m.data[a * dim + i]) -
                                  static_cast<double>(m.data[b * dim + i]));
                best = std::min(best, d);
            }
        all.push_back({v, best});
    }
    std::sort(all.begin(), all.end(), [](const OracleNeighbour& x, const OracleNeighbour& y) {
        return x.distance != y.distance ? x.distance < y.distance : x.view < y.view;
    });
    if (per_model) {
        std::vector<OracleNeighbour> first;
        std::set<std::uint32_t> seen;
        for (const OracleNeighbour& n : all)
            if (seen.insert(m.row_info[setup.view_first_row[n.view]].model).second)
                first.push_back(n);
        all = std::move(first);
    }
    if (all.size() > k) all.resize(k);
    return all;
}

void expect_matches_oracle(const esf::DescriptorMatrix& m, const std::vector<std::string>& groups,
                           const std::vector<float>& weights, std::size_t k, bool per_model) {
    SCOPED_TRACE(per_model ? "one view per model" : "every view");
    const esf::detail::LomoSetup setup = esf::detail::lomo_setup(m, groups, "test");
    const esf::KnnIndex index = esf::detail::lomo_index(m, setup, weights, 1, per_model);
    esf::SyntheticOptions options;
    options.one_view_per_model = per_model;
    options.k = k;
    options.groups = groups;
    options.weights = weights;
    options.threads = 2;
    const EvaluationReport report = esf::evaluate_synthetic(m, options);
    ASSERT_EQ(report.queries.size(), setup.views());
    for (std::size_t q = 0; q < setup.views(); ++q) {
        const std::vector<OracleNeighbour> expected = oracle(m, setup, q, k, weights, per_model);
        const std::vector<esf::KnnNeighbour> got = esf::detail::lomo_search(index, setup, q, k);
        ASSERT_EQ(got.size(), expected.size()) << "query " << q;
        for (std::size_t j = 0; j < got.size(); ++j) {
            EXPECT_EQ(got[j].view, expected[j].view) << "query " << q << " rank " << j;
            EXPECT_NEAR(got[j].distance, expected[j].distance, 1e-9 * expected[j].distance);
        }
        // The report's line of the query agrees with the oracle.
        const esf::QueryResult& line = report.queries[q];
        const std::string truth = m.categories[setup.view_category[q]];
        EXPECT_EQ(line.true_class, truth);
        EXPECT_EQ(line.predicted, m.categories[setup.view_category[expected[0].view]]);
        std::size_t rank = 0;
        for (std::size_t j = 0; j < expected.size() && !rank; ++j)
            if (m.categories[setup.view_category[expected[j].view]] == truth) rank = j + 1;
        EXPECT_EQ(line.rank, rank) << "query " << q;
    }
}

TEST(EvaluateSynthetic, LeaveOneModelOutEqualsBruteForce) {
    const esf::DescriptorMatrix m = random_matrix(3, 4, 6, 48, 1, 7);
    expect_matches_oracle(m, {}, {}, 5, false);
    expect_matches_oracle(m, {}, {}, 5, true);
}

TEST(EvaluateSynthetic, MultiSignatureWeightedGroupsEqualBruteForce) {
    const esf::DescriptorMatrix m = random_matrix(3, 4, 5, 40, 3, 11);
    std::vector<std::string> groups;
    for (std::size_t i = 0; i < m.models.size(); ++i) groups.push_back(std::to_string(i % 5));
    std::vector<float> weights(40);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 2.0f);
    for (float& w : weights) w = u(rng);
    for (const bool per_model : {false, true}) {
        expect_matches_oracle(m, groups, weights, 7, per_model);
        expect_matches_oracle(m, {}, weights, 3, per_model);
    }
}

TEST(EvaluateSynthetic, GroupsLeaveTwinsOut) {
    // Two categories; model 0 and model 1 of category c0 are identical copies.
    esf::DescriptorMatrix m = random_matrix(2, 3, 4, 16, 1, 5);
    const std::size_t dim = 16, views = 4;
    std::copy(m.data.begin(), m.data.begin() + views * dim, m.data.begin() + views * dim);
    esf::SyntheticOptions options;
    options.k = 1;
    options.max_queries = 0;
    EvaluationReport lomo = esf::evaluate_synthetic(m, options);
    EXPECT_EQ(lomo.test_set, "leave-one-model-out");
    EXPECT_EQ(lomo.queries[0].distance, 0.0);  // its twin's view
    options.groups = {"twins", "twins", "c0_m2", "c1_m0", "c1_m1", "c1_m2"};
    EvaluationReport logo = esf::evaluate_synthetic(m, options);
    EXPECT_EQ(logo.test_set, "leave-one-group-out");
    EXPECT_GT(logo.queries[0].distance, 0.0);
}

TEST(EvaluateSynthetic, ThreadCountDoesNotChangeResults) {
    const esf::DescriptorMatrix m = random_matrix(4, 5, 8, 64, 2, 13);
    esf::SyntheticOptions options;
    options.threads = 1;
    const EvaluationReport one = esf::evaluate_synthetic(m, options);
    options.threads = 4;
    const EvaluationReport four = esf::evaluate_synthetic(m, options);
    ASSERT_EQ(one.queries.size(), four.queries.size());
    for (std::size_t q = 0; q < one.queries.size(); ++q) {
        EXPECT_EQ(one.queries[q].predicted, four.queries[q].predicted);
        EXPECT_EQ(one.queries[q].rank, four.queries[q].rank);
        EXPECT_EQ(one.queries[q].distance, four.queries[q].distance);
    }
    EXPECT_EQ(one.confusion, four.confusion);
    EXPECT_EQ(one.top1, four.top1);
    EXPECT_EQ(four.threads, 4);
}

TEST(EvaluateSynthetic, MaxQueriesTakesEvenlySpacedViews) {
    const esf::DescriptorMatrix m = random_matrix(2, 3, 10, 16, 1, 17);
    esf::SyntheticOptions options;
    options.max_queries = 6;
    const EvaluationReport r = esf::evaluate_synthetic(m, options);
    ASSERT_EQ(r.queries.size(), 6u);
    EXPECT_EQ(r.queries[0].file, "c0/m0#0");
    EXPECT_EQ(r.queries[1].file, "c0/m1#0");  // view 10 of 60
    EXPECT_EQ(esf::detail::lomo_queries(60, 6), (std::vector<std::size_t>{0, 10, 20, 30, 40, 50}));
    EXPECT_EQ(esf::detail::lomo_queries(3, 0).size(), 3u);
    EXPECT_EQ(esf::detail::lomo_queries(3, 9).size(), 3u);
}

TEST(EvaluateSynthetic, GroupsFromACatalog) {
    const esf::DescriptorMatrix m = random_matrix(2, 2, 2, 8, 1, 19);
    esf::Catalog catalog;
    catalog.entries.push_back({"c0/m0.ply", "c0", "shared", 0.1, true});
    catalog.entries.push_back({"c1/m1.ply", "c1", "shared", 0.1, true});
    catalog.entries.push_back({"c1/m0.ply", "c1", "", 0.1, true});
    const std::vector<std::string> groups = esf::model_groups(m, catalog);
    ASSERT_EQ(groups.size(), 4u);
    EXPECT_EQ(groups[0], groups[3]);  // both "shared"
    EXPECT_NE(groups[1], groups[0]);  // no entry: its own group
    EXPECT_NE(groups[2], groups[1]);  // an empty group: its own
    const std::vector<std::string> stored = esf::stored_model_groups(m);
    EXPECT_EQ(stored[0], "model:c0/m0");
}

TEST(EvaluateSynthetic, RejectsBadInput) {
    const esf::DescriptorMatrix one = random_matrix(1, 1, 3, 8, 1, 1);
    EXPECT_EQ(error_of([&] { esf::evaluate_synthetic(one); }),
              "evaluate_synthetic: the views belong to 1 group; leaving one out needs at least "
              "two");
    const esf::DescriptorMatrix m = random_matrix(2, 2, 2, 8, 1, 1);
    esf::SyntheticOptions options;
    options.groups = {"a"};
    EXPECT_EQ(error_of([&] { esf::evaluate_synthetic(m, options); }),
              "evaluate_synthetic: 1 groups for 4 models");
    options.groups = {"a", "a", "a", "a"};
    EXPECT_NE(error_of([&] { esf::evaluate_synthetic(m, options); }).find("1 group"),
              std::string::npos);
    options.groups.clear();
    options.k = 0;
    EXPECT_EQ(error_of([&] { esf::evaluate_synthetic(m, options); }),
              "evaluate_synthetic: k must be >= 1");
    EXPECT_THROW(esf::evaluate_synthetic(esf::DescriptorMatrix{}), std::invalid_argument);
}

/// Whether row `a` of `x` and row `b` of `y` are of one model (category and name).
bool same_model(const esf::DescriptorMatrix& x, std::size_t a, const esf::DescriptorMatrix& y,
                std::size_t b) {
    return x.categories[x.row_info[a].category] == y.categories[y.row_info[b].category] &&
           x.models[x.row_info[a].model].name == y.models[y.row_info[b].model].name;
}

/// L1 distance between row `a` of `x` and row `b` of `y`.
double row_l1(const esf::DescriptorMatrix& x, std::size_t a, const esf::DescriptorMatrix& y,
              std::size_t b) {
    double d = 0.0;
    for (std::size_t i = 0; i < x.row(a).size(); ++i)
        d += std::abs(static_cast<double>(x.row(a)[i]) - static_cast<double>(y.row(b)[i]));
    return d;
}

TEST(EvaluateHeldOut, EqualsBruteForceOverTheOtherModels) {
    // The same models (c<i>/m<j>), other views: each query's own model is left out.
    const esf::DescriptorMatrix db = random_matrix(3, 4, 5, 24, 1, 7);
    const esf::DescriptorMatrix queries = random_matrix(3, 4, 2, 24, 1, 23);
    esf::SyntheticOptions options;
    options.k = 4;
    options.threads = 2;
    const EvaluationReport report = esf::evaluate_held_out(db, queries, {}, options);
    ASSERT_EQ(report.queries.size(), queries.rows());
    for (std::size_t q = 0; q < queries.rows(); ++q) {
        const esf::DescriptorRow& qr = queries.row_info[q];
        std::vector<std::pair<double, std::size_t>> all;
        for (std::size_t r = 0; r < db.rows(); ++r) {
            if (same_model(queries, q, db, r)) continue;  // left out
            const double d = row_l1(queries, q, db, r);
            all.emplace_back(d, r);
        }
        std::sort(all.begin(), all.end());
        const std::string truth = queries.categories[qr.category];
        const esf::QueryResult& line = report.queries[q];
        EXPECT_EQ(line.true_class, truth);
        EXPECT_EQ(line.predicted, db.categories[db.row_info[all[0].second].category]) << q;
        std::size_t rank = 0;
        for (std::size_t j = 0; j < options.k && !rank; ++j)
            if (db.categories[db.row_info[all[j].second].category] == truth) rank = j + 1;
        EXPECT_EQ(line.rank, rank) << "query " << q;
        EXPECT_NEAR(line.distance, all[0].first, 1e-6);
    }
    EXPECT_EQ(report.test_set, "held-out views");
    // A database's own views as held-out queries: leave-one-model-out exactly.
    const EvaluationReport self = esf::evaluate_held_out(db, db, {}, options);
    const EvaluationReport lomo = esf::evaluate_synthetic(db, options);
    ASSERT_EQ(self.queries.size(), lomo.queries.size());
    for (std::size_t q = 0; q < self.queries.size(); ++q) {
        EXPECT_EQ(self.queries[q].predicted, lomo.queries[q].predicted) << q;
        EXPECT_EQ(self.queries[q].rank, lomo.queries[q].rank) << q;
        EXPECT_EQ(self.queries[q].distance, lomo.queries[q].distance) << q;
    }
    EXPECT_EQ(error_of([&] { esf::evaluate_held_out(db, queries, {"g"}, options); }),
              "evaluate_held_out: 1 query groups for 12 models");
}

TEST(EvaluateHeldOut, AViewOfSeveralSignaturesIsAsNearAsItsNearest) {
    // Database views of 1 to 3 signatures (occluded copies); queries of one.
    const esf::DescriptorMatrix db = random_matrix(3, 4, 5, 24, 3, 11);
    const esf::DescriptorMatrix queries = random_matrix(3, 4, 2, 24, 1, 29);
    esf::SyntheticOptions options;
    options.k = 3;
    const EvaluationReport report = esf::evaluate_held_out(db, queries, {}, options);
    ASSERT_EQ(report.queries.size(), queries.rows());
    for (std::size_t q = 0; q < queries.rows(); ++q) {
        // Brute force: each view of another model at its nearest signature.
        std::map<std::pair<std::uint32_t, int>, double> views;
        for (std::size_t r = 0; r < db.rows(); ++r) {
            if (same_model(queries, q, db, r)) continue;  // left out
            const esf::DescriptorRow& dr = db.row_info[r];
            const double d = row_l1(queries, q, db, r);
            const auto key = std::make_pair(dr.model, dr.view_index);
            const auto it = views.find(key);
            views[key] = it == views.end() ? d : std::min(it->second, d);
        }
        std::vector<std::pair<double, std::uint32_t>> all;  // (distance, model)
        for (const auto& [key, d] : views) all.emplace_back(d, key.first);
        std::sort(all.begin(), all.end());
        const esf::QueryResult& line = report.queries[q];
        EXPECT_NEAR(line.distance, all[0].first, 1e-6) << q;
        EXPECT_EQ(line.predicted, db.models[all[0].second].category) << q;
    }
    // Queries of several signatures a view are refused.
    EXPECT_NE(error_of([&] {
                  esf::evaluate_held_out(queries, db, {}, options);
              }).find("needs queries of one signature per view"),
              std::string::npos);
}

// ---- test sets against a database -----------------------------------------------------------

class EvaluateTestSet : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("esf_evaluation_test_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_ / "clouds");
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path dir_;
};

esf::Points box_points(const Eigen::Vector3f& size, std::uint64_t seed) {
    esf::Points points;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int i = 0; i < 2000; ++i) {
        Eigen::Vector3f p(u(rng), u(rng), u(rng));
        const int face = i % 6;
        p[face / 2] = float(face % 2);
        points.push_back(p.cwiseProduct(size) + Eigen::Vector3f(0, 0, 1));
    }
    return points;
}

TEST_F(EvaluateTestSet, ClassifiesSkipsAndReportsFailures) {
    // A database of two classes, each one model with one view: a cube and a flat plate.
    const std::string db_path = (dir_ / "db.sqlite").string();
    esf::test::write_one_view_database(db_path, {{"cube", box_points({0.08f, 0.08f, 0.08f}, 1)},
                                                 {"plate", box_points({0.12f, 0.12f, 0.004f}, 2)}});
    // Queries: other samples of the same shapes, a missing file, a class the database lacks.
    for (const auto& [name, size, seed] :
         {std::tuple{"cube", Eigen::Vector3f(0.08f, 0.08f, 0.08f), 7},
          std::tuple{"plate", Eigen::Vector3f(0.12f, 0.12f, 0.004f), 8}}) {
        esf::PointCloud cloud;
        cloud.points = box_points(size, static_cast<std::uint64_t>(seed));
        cloud.width = static_cast<std::uint32_t>(cloud.points.size());
        esf::write_pcd((dir_ / "clouds" / (std::string(name) + ".pcd")).string(), cloud);
    }
    const std::string csv = (dir_ / "set.csv").string();
    {
        std::ofstream out(csv);
        out << "file,class\nclouds/cube.pcd,cube\nclouds/plate.pcd,plate\n"
            << "clouds/missing.pcd,cube\nclouds/cube.pcd,sphere\n";
    }
    const esf::Recognizer recognizer(db_path);
    esf::EvaluationOptions eval;
    eval.k = 2;
    eval.threads = 2;
    std::size_t calls = 0;
    eval.progress = [&](std::size_t done, std::size_t total) {
        ++calls;
        EXPECT_LE(done, total);
        EXPECT_EQ(total, 3u);
    };
    const EvaluationReport r = esf::evaluate_test_set(recognizer, esf::read_test_set(csv), eval);
    EXPECT_EQ(calls, 3u);
    EXPECT_EQ(r.mode, "test set");
    EXPECT_EQ(r.database, db_path);
    EXPECT_EQ(r.descriptor, "esf");
    EXPECT_FALSE(r.weighted);
    EXPECT_EQ(r.samples, 2u);
    EXPECT_DOUBLE_EQ(r.top1, 1.0);
    EXPECT_DOUBLE_EQ(r.topk, 1.0);
    EXPECT_EQ(r.skipped, 1u);
    ASSERT_EQ(r.missing_classes.size(), 1u);
    EXPECT_EQ(r.missing_classes[0].class_name, "sphere");
    ASSERT_EQ(r.failed, 1u);
    EXPECT_NE(r.failures[0].file.find("missing.pcd"), std::string::npos);
    EXPECT_EQ(r.confusion_columns, (std::vector<std::string>{"cube", "plate"}));
    EXPECT_GT(r.describe_ms, 0.0);
    EXPECT_GT(r.match_ms, 0.0);
    EXPECT_EQ(r.threads, 2);
    eval.k = 0;
    EXPECT_THROW(esf::evaluate_test_set(recognizer, esf::read_test_set(csv), eval),
                 std::invalid_argument);
}

}  // namespace
