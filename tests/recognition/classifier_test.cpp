#include "esf/recognition/classifier.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "recognition/knn_synthetic.hpp"
#include "support/error_of.hpp"

namespace {

using esf::Classification;
using esf::Classifier;
using esf::ClassifierOptions;
using esf::KnnIndex;
using esf::ViewLabel;

ViewLabel label(const std::string& cls, int class_id, const std::string& model, int view) {
    ViewLabel l;
    l.class_name = cls;
    l.class_id = class_id;
    l.model_name = model;
    l.model_id = view * 10;
    l.view = view;
    l.pose(0, 3) = static_cast<float>(view);  // a translation that tells the views apart
    return l;
}

/// 1-D views at the given positions (exact binary fractions, so distances are exact); the
/// majority rule unless told otherwise.
Classifier make(const std::vector<float>& positions, std::vector<ViewLabel> labels, std::size_t k,
                esf::VoteRule vote = esf::VoteRule::kMajority) {
    ClassifierOptions options;
    options.k = k;
    options.vote = vote;
    return Classifier(KnnIndex(positions, 1), std::move(labels), options);
}

TEST(Classifier, MajorityWinsOverTheNearestView) {
    // query 0; views at 0.125 (mug), 0.25 (bowl), 0.375 (bowl), 0.5 (mug), 0.625 (bowl),
    // 4 (mug). k = 5: bowl 3 votes, mug 2 votes -> bowl, confidence 3/5, best bowl view = 1.
    const Classifier c = make(
        {0.125f, 0.25f, 0.375f, 0.5f, 0.625f, 4.0f},
        {label("mug", 0, "mug_a", 0), label("bowl", 1, "bowl_a", 1), label("bowl", 1, "bowl_b", 2),
         label("mug", 0, "mug_a", 3), label("bowl", 1, "bowl_a", 4), label("mug", 0, "mug_b", 5)},
        5);
    const Classification r = c.classify(std::vector<float>{0.0f});
    EXPECT_EQ(r.class_name, "bowl");
    EXPECT_EQ(r.class_id, 1);
    EXPECT_DOUBLE_EQ(r.confidence, 0.6);
    EXPECT_EQ(r.best_model, "bowl_a");
    EXPECT_EQ(r.best_model_id, 10);
    EXPECT_EQ(r.best_view, 1);
    EXPECT_EQ(r.best_index, 1u);
    EXPECT_EQ(r.best_distance, 0.25);
    EXPECT_EQ(r.pose(0, 3), 1.0f);
    ASSERT_EQ(r.neighbours.size(), 5u);
    const std::vector<std::string> classes = {"mug", "bowl", "bowl", "mug", "bowl"};
    for (std::size_t i = 0; i < 5; ++i) {
        EXPECT_EQ(r.neighbours[i].class_name, classes[i]);
        EXPECT_EQ(r.neighbours[i].index, i);
        EXPECT_EQ(r.neighbours[i].view, static_cast<int>(i));
        EXPECT_EQ(r.neighbours[i].distance, 0.125 * static_cast<double>(i + 1));
        EXPECT_EQ(r.neighbours[i].pose(0, 3), static_cast<float>(i));
    }
    ASSERT_EQ(r.votes.size(), 2u);
    EXPECT_EQ(r.votes[0].class_name, "bowl");
    EXPECT_EQ(r.votes[0].votes, 3u);
    EXPECT_EQ(r.votes[0].distance_sum, 0.25 + 0.375 + 0.625);
    EXPECT_EQ(r.votes[1].class_name, "mug");
    EXPECT_EQ(r.votes[1].votes, 2u);
    EXPECT_EQ(r.votes[1].distance_sum, 0.125 + 0.5);
}

TEST(Classifier, NearestRuleNamesTheNearestViewsClassAgainstAMajority) {
    // The views of MajorityWinsOverTheNearestView: the nearest (0.125) is a mug, bowl has 3 of 5
    // votes -> mug, confidence 2/5, best view 0; the votes list the mug first, then the bowl.
    const Classifier c = make(
        {0.125f, 0.25f, 0.375f, 0.5f, 0.625f, 4.0f},
        {label("mug", 0, "mug_a", 0), label("bowl", 1, "bowl_a", 1), label("bowl", 1, "bowl_b", 2),
         label("mug", 0, "mug_a", 3), label("bowl", 1, "bowl_a", 4), label("mug", 0, "mug_b", 5)},
        5, esf::VoteRule::kNearest);
    const Classification r = c.classify(std::vector<float>{0.0f});
    EXPECT_EQ(r.class_name, "mug");
    EXPECT_EQ(r.class_id, 0);
    EXPECT_DOUBLE_EQ(r.confidence, 0.4);
    EXPECT_EQ(r.best_model, "mug_a");
    EXPECT_EQ(r.best_view, 0);
    EXPECT_EQ(r.best_distance, 0.125);
    ASSERT_EQ(r.votes.size(), 2u);
    EXPECT_EQ(r.votes[0].class_name, "mug");
    EXPECT_EQ(r.votes[0].votes, 2u);
    EXPECT_EQ(r.votes[1].class_name, "bowl");
    EXPECT_EQ(r.votes[1].votes, 3u);
    EXPECT_EQ(ClassifierOptions{}.vote, esf::VoteRule::kNearest);
}

TEST(Classifier, NearestRuleOrdersTheOtherClassesByVotes) {
    // query 0; k = 6: cup nearest (1 vote), then bowl x2, mug x3 -> cup; then mug (3), bowl (2).
    const Classifier c =
        make({0.125f, 0.25f, 0.375f, 0.5f, 0.625f, 0.75f},
             {label("cup", 2, "c", 0), label("bowl", 1, "b", 1), label("mug", 0, "m", 2),
              label("bowl", 1, "b", 3), label("mug", 0, "m", 4), label("mug", 0, "m", 5)},
             6, esf::VoteRule::kNearest);
    const Classification r = c.classify(std::vector<float>{0.0f});
    EXPECT_EQ(r.class_name, "cup");
    EXPECT_DOUBLE_EQ(r.confidence, 1.0 / 6.0);
    ASSERT_EQ(r.votes.size(), 3u);
    EXPECT_EQ(r.votes[1].class_name, "mug");
    EXPECT_EQ(r.votes[2].class_name, "bowl");
}

TEST(Classifier, VoteRuleNames) {
    EXPECT_STREQ(esf::to_string(esf::VoteRule::kNearest), "nearest");
    EXPECT_EQ(esf::parse_enum<esf::VoteRule>("majority"), esf::VoteRule::kMajority);
    EXPECT_EQ(esf::parse_enum<esf::VoteRule>(esf::to_string(esf::VoteRule::kNearest)),
              esf::VoteRule::kNearest);
    EXPECT_THROW(esf::parse_enum<esf::VoteRule>("Majority"), std::invalid_argument);
}

TEST(Classifier, OneNearestNeighbourIsTheNearestViewsClass) {
    const Classifier c =
        make({0.125f, 0.25f, 0.375f},
             {label("mug", 0, "m", 0), label("bowl", 1, "b", 1), label("bowl", 1, "b", 2)}, 1);
    const Classification r = c.classify(std::vector<float>{0.0f});
    EXPECT_EQ(r.class_name, "mug");
    EXPECT_EQ(r.confidence, 1.0);
    EXPECT_EQ(r.neighbours.size(), 1u);
}

TEST(Classifier, EqualVotesGoToTheSmallerDistanceSum) {
    // query 0; k = 4: mug at 0.125 and 0.75 (sum 0.875), bowl at 0.25 and 0.5 (sum 0.75).
    // Two votes each; the nearest view is a mug, but the bowl's sum is smaller -> bowl.
    const Classifier c = make({0.125f, 0.25f, 0.5f, 0.75f},
                              {label("mug", 0, "m", 0), label("bowl", 1, "b", 1),
                               label("bowl", 1, "b", 2), label("mug", 0, "m", 3)},
                              4);
    const Classification r = c.classify(std::vector<float>{0.0f});
    EXPECT_EQ(r.class_name, "bowl");
    EXPECT_EQ(r.confidence, 0.5);
    EXPECT_EQ(r.best_index, 1u);
}

TEST(Classifier, EqualVotesAndSumsGoToTheNearerView) {
    // query 0; k = 4: mug at 0.125 and 0.625 (sum 0.75), bowl at 0.25 and 0.5 (sum 0.75).
    const Classifier c = make({0.125f, 0.25f, 0.5f, 0.625f},
                              {label("mug", 0, "m", 0), label("bowl", 1, "b", 1),
                               label("bowl", 1, "b", 2), label("mug", 0, "m", 3)},
                              4);
    const Classification r = c.classify(std::vector<float>{0.0f});
    EXPECT_EQ(r.class_name, "mug");
    EXPECT_EQ(r.best_index, 0u);
    ASSERT_EQ(r.votes.size(), 2u);
    EXPECT_EQ(r.votes[0].distance_sum, r.votes[1].distance_sum);
}

TEST(Classifier, EqualDistancesTieByViewId) {
    // Views 0 (bowl) and 1 (mug) at the same distance from the query: view 0 is nearer by id.
    const Classifier c =
        make({1.0f, -1.0f, 3.0f},
             {label("bowl", 1, "b", 0), label("mug", 0, "m", 1), label("mug", 0, "m", 2)}, 1);
    EXPECT_EQ(c.classify(std::vector<float>{0.0f}).class_name, "bowl");
    // With k = 2 both vote once, with equal sums: the nearer (lower id) wins again.
    const Classifier c2 =
        make({1.0f, -1.0f, 3.0f},
             {label("bowl", 1, "b", 0), label("mug", 0, "m", 1), label("mug", 0, "m", 2)}, 2);
    EXPECT_EQ(c2.classify(std::vector<float>{0.0f}).class_name, "bowl");
    // With k = 3 the mugs have two votes.
    const Classifier c3 =
        make({1.0f, -1.0f, 3.0f},
             {label("bowl", 1, "b", 0), label("mug", 0, "m", 1), label("mug", 0, "m", 2)}, 3);
    EXPECT_EQ(c3.classify(std::vector<float>{0.0f}).class_name, "mug");
}

TEST(Classifier, KLargerThanTheIndexUsesEveryView) {
    const Classifier c =
        make({0.0f, 1.0f}, {label("mug", 0, "m", 0), label("bowl", 1, "b", 1)}, 10);
    const Classification r = c.classify(std::vector<float>{0.25f});
    EXPECT_EQ(r.neighbours.size(), 2u);
    EXPECT_EQ(r.class_name, "mug");
    EXPECT_EQ(r.confidence, 0.5);
}

TEST(Classifier, DefaultKIsTen) { EXPECT_EQ(ClassifierOptions{}.k, 10u); }

TEST(Classifier, GroupedViewsVoteOnce) {
    // Two rows for view 0 (mug), one for view 1 (bowl), one for view 2 (bowl); k = 3.
    // query 0: view 0 = min(0.125, 0.25), view 1 = 0.5, view 2 = 0.75 -> bowl 2 : mug 1.
    const std::vector<float> rows = {0.125f, 0.25f, 0.5f, 0.75f};
    const std::vector<std::uint32_t> views = {0, 0, 1, 2};
    ClassifierOptions options;
    options.k = 3;
    options.vote = esf::VoteRule::kMajority;
    const Classifier c(
        KnnIndex(rows, 1, views),
        {label("mug", 0, "m", 0), label("bowl", 1, "b", 1), label("bowl", 1, "b", 2)}, options);
    const Classification r = c.classify(std::vector<float>{0.0f});
    EXPECT_EQ(r.class_name, "bowl");
    ASSERT_EQ(r.neighbours.size(), 3u);
    EXPECT_EQ(r.neighbours[0].class_name, "mug");
    EXPECT_EQ(r.neighbours[0].distance, 0.125);
}

TEST(Classifier, BatchMatchesSingleForOneAndTwoThreads) {
    const std::size_t dim = 640, n = 600;
    const std::vector<float> rows = esf::detail::esf_like_rows(n, dim, 3, 1);
    std::vector<ViewLabel> labels;
    for (std::size_t v = 0; v < n; ++v)
        labels.push_back(label("class" + std::to_string(v % 7), static_cast<int>(v % 7),
                               "model" + std::to_string(v % 31), static_cast<int>(v)));
    const Classifier c(KnnIndex(rows, dim), labels);
    const std::vector<float> queries = esf::detail::esf_like_rows(12, dim, 4, 1);
    const auto one = c.classify_batch(queries, 1);
    const auto two = c.classify_batch(queries, 2);
    ASSERT_EQ(one.size(), 12u);
    ASSERT_EQ(two.size(), 12u);
    for (std::size_t q = 0; q < 12; ++q) {
        const Classification single = c.classify({queries.data() + q * dim, dim});
        for (const Classification* r : {&one[q], &two[q]}) {
            EXPECT_EQ(r->class_name, single.class_name);
            EXPECT_EQ(r->confidence, single.confidence);
            EXPECT_EQ(r->best_index, single.best_index);
            ASSERT_EQ(r->neighbours.size(), 10u);
            for (std::size_t i = 0; i < 10; ++i) {
                EXPECT_EQ(r->neighbours[i].index, single.neighbours[i].index);
                EXPECT_EQ(r->neighbours[i].distance, single.neighbours[i].distance);
            }
        }
    }
}

/// The message of the std::invalid_argument f() throws.
template <typename F>
std::string error_of(F&& f) {
    return esf::test::error_of<std::invalid_argument>(std::forward<F>(f));
}

TEST(ClassifierErrors, BadConstruction) {
    const std::vector<float> rows = {0.0f, 1.0f};
    const std::vector<ViewLabel> two = {label("mug", 0, "m", 0), label("bowl", 1, "b", 1)};
    EXPECT_EQ(error_of([&] { Classifier(KnnIndex(), {}); }), "classifier: the index is empty");
    EXPECT_EQ(error_of([&] { Classifier(KnnIndex(rows, 1), {two[0]}); }),
              "classifier: 1 view labels for an index of 2 views");
    ClassifierOptions zero;
    zero.k = 0;
    EXPECT_EQ(error_of([&] { Classifier(KnnIndex(rows, 1), two, zero); }),
              "classifier: k must be >= 1");
    EXPECT_EQ(error_of([&] {
                  Classifier(KnnIndex(rows, 1), {two[0], label("", 1, "b", 1)});
              }),
              "classifier: view 1 has no class name");
    EXPECT_EQ(error_of([&] {
                  Classifier(KnnIndex(rows, 1), {two[0], label("mug", 3, "m", 1)});
              }),
              "classifier: class 'mug' has two ids (0 and 3, view 1)");
}

TEST(ClassifierErrors, BadQueries) {
    const Classifier c = make({0.0f, 1.0f}, {label("mug", 0, "m", 0), label("bowl", 1, "b", 1)}, 1);
    EXPECT_EQ(error_of([&] {
                  c.classify(std::vector<float>{1.0f, 2.0f});
              }),
              "knn search: query has 2 values, the index has dimension 1");
    EXPECT_EQ(
        error_of([&] { c.classify(std::vector<float>{std::numeric_limits<float>::quiet_NaN()}); }),
        "knn search: query value 0 is NaN");
    EXPECT_EQ(error_of([&] { esf::classify_neighbours({}, c.labels()); }),
              "classify: no neighbours to vote");
    const std::vector<esf::KnnNeighbour> out_of_range = {{5, 5, 0.0}};
    EXPECT_EQ(error_of([&] { esf::classify_neighbours(out_of_range, c.labels()); }),
              "classify: view 5 has no label (2 labels)");
}

}  // namespace
