// The k-nearest-neighbour index's errors: bad input, bad queries, an empty index; block
// weights expanded over the bins.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "esf/recognition/knn_index.hpp"
#include "support/error_of.hpp"
#include "support/knn_oracle.hpp"

namespace esf::test {
namespace {

TEST(KnnIndex, ExpandBlockWeights) {
    const std::vector<float> blocks = {0.5f, 2.0f};
    EXPECT_EQ(esf::expand_block_weights(blocks, 3),
              (std::vector<float>{0.5f, 0.5f, 0.5f, 2.0f, 2.0f, 2.0f}));
    EXPECT_EQ(esf::expand_block_weights(std::vector<float>(10, 1.0f), 64).size(), 640u);
}

/// The message of the std::invalid_argument f() throws.
template <typename F>
std::string error_of(F&& f) {
    return esf::test::error_of<std::invalid_argument>(std::forward<F>(f));
}

TEST(KnnIndexErrors, BadIndexInput) {
    const std::vector<float> rows = {0, 1, 2, 3, 4, 5};
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 0); }), "knn index: dimension must be > 0");
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 4); }),
              "knn index: 6 values are not a whole number of rows of dimension 4");
    std::vector<float> bad = rows;
    bad[4] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(error_of([&] { KnnIndex(bad, 2); }), "knn index: row 2 value 0 is NaN");
    bad[4] = -std::numeric_limits<float>::infinity();
    EXPECT_EQ(error_of([&] { KnnIndex(bad, 2); }), "knn index: row 2 value 0 is -inf");
    KnnIndexOptions options;
    options.weights = {1.0f};
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, options); }),
              "knn index: 1 weights for dimension 2");
    options.weights = {1.0f, -1.0f};
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, options); }),
              "knn index: weight 1 is -1 (must be finite and >= 0)");
    options.weights = {std::numeric_limits<float>::quiet_NaN(), 1.0f};
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, options); }),
              "knn index: weight 0 is nan (must be finite and >= 0)");
    options.weights.clear();
    options.sketch_group = -1;
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, options); }),
              "knn index: sketch_group must be >= 0, got -1");
    options.sketch_group = 0;
    options.threads = -2;
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, options); }),
              "thread count must be >= 0 (0 = all cores), got -2");
    const std::vector<std::uint32_t> two_views = {0, 1};
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, two_views); }), "knn index: 2 view ids for 3 rows");
    options.threads = 0;
    options.view_families = {0, 1};
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, options); }),
              "knn index: 2 view families for 3 views");
    options.view_families = {0, 2, 2};
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, options); }),
              "knn index: family 1 has no views (families must be numbered 0 .. F-1 without "
              "gaps)");
    options.view_families = {0, 7, 0};
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, options); }),
              "knn index: family 7 out of range (3 views)");
    options.view_families.clear();
    const std::vector<std::uint32_t> gap = {0, 2, 2};
    EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, gap); }),
              "knn index: view 1 has no rows (views must be numbered 0 .. V-1 without gaps)");
    for (Kernels kernel : {Kernels::kAvx2, Kernels::kAvx512}) {
        if (esf::kernels_supported(kernel)) continue;
        options.threads = 0;
        options.kernels = kernel;
        EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, options); }),
                  std::string("knn index: kernels ") + esf::to_string(kernel) +
                      " are not supported by this CPU");
    }
}

TEST(KnnIndexErrors, BadQueries) {
    const std::vector<float> rows = {0, 1, 2, 3, 4, 5};
    const KnnIndex index(rows, 2);
    const std::vector<float> query = {0.5f, 0.5f};
    EXPECT_EQ(error_of([&] {
                  index.search(std::vector<float>{1, 2, 3}, 1);
              }),
              "knn search: query has 3 values, the index has dimension 2");
    EXPECT_EQ(error_of([&] {
                  index.search(std::vector<float>{1, std::numeric_limits<float>::quiet_NaN()}, 1);
              }),
              "knn search: query value 1 is NaN");
    EXPECT_EQ(error_of([&] {
                  index.search(std::vector<float>{std::numeric_limits<float>::infinity(), 0}, 1);
              }),
              "knn search: query value 0 is +inf");
    EXPECT_EQ(error_of([&] { index.search(query, 0); }), "knn search: k must be >= 1");
    EXPECT_EQ(error_of([&] { index.search_batch(query, 0); }), "knn search: k must be >= 1");
    EXPECT_EQ(error_of([&] {
                  index.search_batch(std::vector<float>{1, 2, 3}, 1);
              }),
              "knn search: 3 query values are not a whole number of queries of dimension 2");
    EXPECT_EQ(error_of([&] {
                  index.search_batch(
                      std::vector<float>{1, 2, 3, std::numeric_limits<float>::quiet_NaN()}, 1);
              }),
              "knn search: query 1 value 1 is NaN");
    EXPECT_EQ(error_of([&] { index.distance(query, 3); }),
              "knn index: row 3 out of range (3 rows)");
    EXPECT_EQ(error_of([&] { index.search_batch(query, 1, -1); }),
              "thread count must be >= 0 (0 = all cores), got -1");
}

TEST(KnnIndexErrors, EmptyIndex) {
    const KnnIndex empty;
    EXPECT_TRUE(empty.empty());
    const std::vector<float> query = {0.5f};
    EXPECT_EQ(error_of([&] { empty.search(query, 1); }), "knn search: the index is empty");
    EXPECT_EQ(error_of([&] { empty.search_batch(query, 1); }), "knn search: the index is empty");
    const KnnIndex no_rows(std::vector<float>{}, 1);
    EXPECT_EQ(error_of([&] { no_rows.search(query, 1); }), "knn search: the index is empty");
}

}  // namespace
}  // namespace esf::test
