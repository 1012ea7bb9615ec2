// The k-nearest-neighbour index against brute force in double: ESF-like, real and odd data,
// ties, groups of rows per view, families of views, the sketch that excludes rows.

#include "esf/recognition/knn_index.hpp"

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

#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/io/cloud_io.hpp"
#include "recognition/knn_kernels.hpp"
#include "support/knn_oracle.hpp"
#include "support/test_data.hpp"

namespace esf::test {
namespace {

struct OracleCase {
    std::size_t dim;
    std::size_t k;
    bool weighted;
};

class KnnOracle : public ::testing::TestWithParam<OracleCase> {};

TEST_P(KnnOracle, MatchesBruteForceOnEsfLikeData) {
    const auto [dim, k, weighted] = GetParam();
    const std::size_t n = 2000;
    const std::vector<float> rows = rows_with_duplicates(n, dim, 11 + dim);
    KnnIndexOptions options;
    if (weighted) {
        std::vector<float> block_weights;
        for (std::size_t b = 0; b < (dim + 63) / 64; ++b)
            block_weights.push_back(0.25f * static_cast<float>(b % 5));  // includes weight 0
        options.weights = esf::expand_block_weights(block_weights, 64);
        options.weights.resize(dim);
    }
    const std::vector<float> queries = make_queries(rows, dim, 5);
    for (Kernels kernel : supported_kernels()) {
        options.kernels = kernel;
        const KnnIndex index(rows, dim, options);
        for (std::size_t q = 0; q < queries.size() / dim; ++q) {
            const std::span<const float> query(queries.data() + q * dim, dim);
            const esf::KnnResult got = index.search(query, k);
            expect_same(got.neighbours, brute_force(rows, dim, {}, query, options.weights, k),
                        std::string(esf::to_string(kernel)) + " query " + std::to_string(q));
        }
    }
}

INSTANTIATE_TEST_SUITE_P(DimsKsWeights, KnnOracle,
                         ::testing::Values(OracleCase{640, 1, false}, OracleCase{640, 10, false},
                                           OracleCase{640, 50, false}, OracleCase{640, 10, true},
                                           OracleCase{640, 50, true}, OracleCase{308, 1, true},
                                           OracleCase{308, 10, false}, OracleCase{308, 50, true},
                                           OracleCase{64, 1, false}, OracleCase{64, 10, true},
                                           OracleCase{64, 50, false}, OracleCase{352, 10, false},
                                           OracleCase{13, 10, false}),
                         [](const ::testing::TestParamInfo<OracleCase>& param_info) {
                             return "dim" + std::to_string(param_info.param.dim) + "_k" +
                                    std::to_string(param_info.param.k) +
                                    (param_info.param.weighted ? "_weighted" : "");
                         });

TEST(KnnIndex, MatchesBruteForceOnRealEsfDescriptors) {
    // ESF of the labelled real clusters, twice with different seeds: one set indexed (weighted
    // with the paper's block weights and unweighted), the other as queries.
    ESF_REQUIRE_DATA("real/objects");
    std::vector<esf::Points> clouds;
    for (const auto& entry :
         std::filesystem::directory_iterator(esf::test::data_file("real/objects"))) {
        if (entry.path().extension() == ".pcd")
            clouds.push_back(esf::read_cloud(entry.path().string()).points);
    }
    ASSERT_GE(clouds.size(), 50u);
    std::vector<float> rows, queries;
    for (std::uint64_t seed : {1, 2}) {
        esf::EsfOptions options;
        options.seed = seed;
        options.samples = 5000;
        for (const auto& item : esf::compute_esf_batch(clouds, options)) {
            ASSERT_TRUE(item.ok()) << item.error;
            auto& out = seed == 1 ? rows : queries;
            out.insert(out.end(), item.result.descriptor.begin(), item.result.descriptor.end());
        }
    }
    const std::size_t dim = esf::kEsfSize;
    const std::vector<float> paper_weights = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f,
                                              1.0f, 0.5f, 2.0f, 2.0f, 1.0f};
    for (bool weighted : {false, true}) {
        KnnIndexOptions options;
        if (weighted) options.weights = esf::expand_block_weights(paper_weights, esf::kEsfBins);
        const KnnIndex index(rows, dim, options);
        std::size_t self_match = 0;
        for (std::size_t q = 0; q < clouds.size(); ++q) {
            const std::span<const float> query(queries.data() + q * dim, dim);
            const auto got = index.search(query, 10).neighbours;
            expect_same(got, brute_force(rows, dim, {}, query, options.weights, 10),
                        "query " + std::to_string(q));
            self_match += got.front().view == q;
        }
        // The same cluster described with another seed is almost always the nearest.
        EXPECT_GE(self_match, clouds.size() * 8 / 10);
    }
}

TEST(KnnIndex, MatchesBruteForceOnUniformNoise) {
    // Independent uniform values defeat the sketch bound (many exact distances); still exact.
    const std::size_t dim = 640, n = 1500;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    std::vector<float> rows(n * dim);
    for (float& v : rows) v = uniform(rng);
    std::vector<float> queries(4 * dim);
    for (float& v : queries) v = uniform(rng);
    const KnnIndex index(rows, dim);
    for (std::size_t q = 0; q < 4; ++q) {
        const std::span<const float> query(queries.data() + q * dim, dim);
        expect_same(index.search(query, 10).neighbours, brute_force(rows, dim, {}, query, {}, 10),
                    "query " + std::to_string(q));
    }
}

TEST(KnnIndex, ExactTiesAreOrderedByViewId) {
    // Values 0..3: every distance is an exact small integer, so many different rows tie
    // exactly and the order within a tie must be by view id.
    const std::size_t dim = 64, n = 3000;
    std::mt19937 rng(17);
    std::uniform_int_distribution<int> value(0, 3);
    std::vector<float> rows(n * dim);
    for (float& v : rows) v = static_cast<float>(value(rng));
    for (Kernels kernel : supported_kernels()) {
        KnnIndexOptions options;
        options.kernels = kernel;
        const KnnIndex index(rows, dim, options);
        for (int q = 0; q < 5; ++q) {
            std::vector<float> query(dim);
            for (float& v : query) v = static_cast<float>(value(rng));
            const auto want = brute_force(rows, dim, {}, query, {}, 50);
            expect_same(index.search(query, 50).neighbours, want, esf::to_string(kernel));
            bool tied = false;
            for (std::size_t i = 1; i < want.size(); ++i)
                tied = tied || want[i].distance == want[i - 1].distance;
            EXPECT_TRUE(tied) << "the case should contain ties";
        }
    }
}

TEST(KnnIndex, HandComputedDistances) {
    // Three 2-D rows; query (1, 1); weights (1, 3).
    //   row 0 (0, 0): 1*1 + 3*1 = 4      row 1 (1, 2): 0 + 3*1 = 3      row 2 (3, 1): 2 + 0 = 2
    const std::vector<float> rows = {0, 0, 1, 2, 3, 1};
    KnnIndexOptions options;
    options.weights = {1.0f, 3.0f};
    const KnnIndex index(rows, 2, options);
    const std::vector<float> query = {1, 1};
    const auto found = index.search(query, 3).neighbours;
    ASSERT_EQ(found.size(), 3u);
    EXPECT_EQ(found[0].view, 2u);
    EXPECT_EQ(found[0].distance, 2.0);
    EXPECT_EQ(found[1].view, 1u);
    EXPECT_EQ(found[1].distance, 3.0);
    EXPECT_EQ(found[2].view, 0u);
    EXPECT_EQ(found[2].distance, 4.0);
    EXPECT_EQ(index.distance(query, 0), 4.0);
    // k larger than the index: every view.
    EXPECT_EQ(index.search(query, 10).neighbours.size(), 3u);
}

TEST(KnnIndex, GroupsTakeTheBestRowOfEachView) {
    // Rows 0..3 of 1-D values; views: rows 0 and 2 -> view 1, row 1 -> view 0, row 3 -> view 2.
    //   query 0.5: row distances 0.5, 1.5, 0.25, 0.25 -> view 1 = min(0.5, 0.25) via row 2,
    //   view 2 = 0.25 via row 3 (tie with view 1: lower view id first), view 0 = 1.5.
    const std::vector<float> rows = {0.0f, 2.0f, 0.75f, 0.25f};
    const std::vector<std::uint32_t> views = {1, 0, 1, 2};
    const KnnIndex index(rows, 1, views);
    EXPECT_EQ(index.views(), 3u);
    EXPECT_TRUE(index.grouped());
    const std::vector<float> query = {0.5f};
    const auto found = index.search(query, 3).neighbours;
    ASSERT_EQ(found.size(), 3u);
    EXPECT_EQ(found[0].view, 1u);
    EXPECT_EQ(found[0].row, 2u);
    EXPECT_EQ(found[0].distance, 0.25);
    EXPECT_EQ(found[1].view, 2u);
    EXPECT_EQ(found[1].row, 3u);
    EXPECT_EQ(found[2].view, 0u);
    EXPECT_EQ(found[2].distance, 1.5);
}

TEST(KnnIndex, GroupsMatchBruteForce) {
    const std::size_t dim = 308, n = 2400;
    const std::vector<float> rows = rows_with_duplicates(n, dim, 23);
    std::mt19937 rng(29);
    std::vector<std::uint32_t> row_views(n);
    for (std::size_t r = 0; r < n; ++r) row_views[r] = static_cast<std::uint32_t>(r % 700);
    std::shuffle(row_views.begin(), row_views.end(), rng);  // 3 or 4 rows per view, scattered
    const std::vector<float> queries = make_queries(rows, dim, 31);
    for (Kernels kernel : supported_kernels()) {
        KnnIndexOptions options;
        options.kernels = kernel;
        const KnnIndex index(rows, dim, row_views, options);
        for (std::size_t k : {std::size_t{1}, std::size_t{10}, std::size_t{50}}) {
            for (std::size_t q = 0; q < queries.size() / dim; ++q) {
                const std::span<const float> query(queries.data() + q * dim, dim);
                expect_same(index.search(query, k).neighbours,
                            brute_force(rows, dim, row_views, query, {}, k),
                            "k " + std::to_string(k) + " query " + std::to_string(q));
            }
        }
    }
}

/// Brute force with families: the per-view brute force, then the first view of each family.
std::vector<KnnNeighbour> brute_force_families(const std::vector<float>& rows, std::size_t dim,
                                               const std::vector<std::uint32_t>& row_views,
                                               const std::vector<std::uint32_t>& families,
                                               std::span<const float> query, std::size_t k) {
    const std::vector<KnnNeighbour> views =
        brute_force(rows, dim, row_views, query, {}, rows.size() / dim);
    std::vector<KnnNeighbour> best;
    std::vector<bool> seen(families.size(), false);
    for (const KnnNeighbour& n : views) {
        if (seen[families[n.view]]) continue;
        seen[families[n.view]] = true;
        if (best.size() < k) best.push_back(n);
    }
    return best;
}

TEST(KnnIndex, FamiliesKeepTheNearestViewOfEach) {
    // 1-D views 0..4 at 0, 1, 2, 3, 10; families {0, 0, 1, 1, 2}. Query 2.4: views by distance
    // 2 (0.4), 3 (0.6), 1 (1.4), 0 (2.4), 4 (7.6) -> families 1 via view 2, 0 via view 1, 2.
    const std::vector<float> rows = {0.0f, 1.0f, 2.0f, 3.0f, 10.0f};
    KnnIndexOptions options;
    options.view_families = {0, 0, 1, 1, 2};
    const KnnIndex index(rows, 1, options);
    EXPECT_EQ(index.families(), 3u);
    EXPECT_EQ(index.family_of(3), 1u);
    const std::vector<float> query = {2.4f};
    const auto found = index.search(query, 5).neighbours;
    ASSERT_EQ(found.size(), 3u);
    EXPECT_EQ(found[0].view, 2u);
    EXPECT_EQ(found[1].view, 1u);
    EXPECT_EQ(found[2].view, 4u);
    EXPECT_NEAR(found[1].distance, 1.4, 1e-6);
    EXPECT_EQ(index.search(query, 1).neighbours.at(0).view, 2u);
}

TEST(KnnIndex, FamiliesMatchBruteForce) {
    const std::size_t dim = 64, n = 3000;
    const std::vector<float> rows = rows_with_duplicates(n, dim, 41);
    std::mt19937 rng(43);
    // Without groups: 3000 views in 60 families of 50 (consecutive, as a database's models);
    // with groups: 1000 views of 3 rows each (scattered), families of 1 to 40 views.
    std::vector<std::uint32_t> consecutive(n), row_views(n), grouped_families(1000);
    for (std::size_t v = 0; v < n; ++v) consecutive[v] = static_cast<std::uint32_t>(v / 50);
    for (std::size_t r = 0; r < n; ++r) row_views[r] = static_cast<std::uint32_t>(r % 1000);
    std::shuffle(row_views.begin(), row_views.end(), rng);
    for (std::size_t v = 0; v < 1000; ++v)
        grouped_families[v] = static_cast<std::uint32_t>(v < 40 ? 0 : 1 + (v - 40) % 80);
    // Skewed, without groups: family 0 holds 2900 views, each of the other 100 one view (the
    // first rows by bound are then mostly family 0's, and the search must look further).
    std::vector<std::uint32_t> skewed(n);
    for (std::size_t v = 0; v < n; ++v)
        skewed[v] = v % 30 == 0 ? static_cast<std::uint32_t>(1 + v / 30) : 0;
    const std::vector<float> queries = make_queries(rows, dim, 47);
    for (Kernels kernel : supported_kernels()) {
        for (const int layout : {0, 1, 2}) {
            const bool grouped = layout == 1;
            KnnIndexOptions options;
            options.kernels = kernel;
            options.view_families = layout == 0 ? consecutive : grouped ? grouped_families : skewed;
            const KnnIndex index =
                grouped ? KnnIndex(rows, dim, row_views, options) : KnnIndex(rows, dim, options);
            const std::vector<std::uint32_t> no_groups;
            for (std::size_t k : {std::size_t{1}, std::size_t{10}, std::size_t{100}}) {
                for (std::size_t q = 0; q < queries.size() / dim; ++q) {
                    const std::span<const float> query(queries.data() + q * dim, dim);
                    expect_same(index.search(query, k).neighbours,
                                brute_force_families(rows, dim, grouped ? row_views : no_groups,
                                                     options.view_families, query, k),
                                std::string(layout == 0 ? "rows"
                                            : grouped   ? "grouped"
                                                        : "skewed") +
                                    " k " + std::to_string(k) + " query " + std::to_string(q));
                }
            }
        }
    }
}

TEST(KnnIndex, LargeBatchesMatchSingleQueriesAndBruteForce) {
    // More rows than the search samples for its cut (one in 8) and than one block of a pass,
    // and full groups of 16 queries that share every pass: a batch gives the single queries'
    // results bit for bit, and brute force's. k = 1 cuts close, so that the k-th distance
    // often lies beyond the cut and needs a second pass; the skewed families leave the seeds
    // in one family, so that the rest of the rows are refined in batches.
    const std::size_t dim = esf::kEsfSize, n = 6000;
    const std::vector<float> rows = rows_with_duplicates(n, dim, 53);
    std::vector<float> queries = make_queries(rows, dim, 59);
    const std::vector<float> fresh = esf::detail::esf_like_rows(21, dim, 61, 1);
    queries.insert(queries.end(), fresh.begin(), fresh.end());
    const std::size_t count = queries.size() / dim;
    ASSERT_EQ(count, 32u);
    std::vector<std::uint32_t> skewed(n);
    for (std::size_t v = 0; v < n; ++v)
        skewed[v] = v % 30 == 0 ? static_cast<std::uint32_t>(1 + v / 30) : 0;
    const std::size_t k_max = 50;
    std::vector<std::vector<KnnNeighbour>> want_views(count), want_families(count);
    for (std::size_t q = 0; q < count; ++q) {
        const std::span<const float> query(queries.data() + q * dim, dim);
        want_views[q] = brute_force(rows, dim, {}, query, {}, k_max);
        want_families[q] = brute_force_families(rows, dim, {}, skewed, query, k_max);
    }
    for (Kernels kernel : supported_kernels()) {
        for (const bool families : {false, true}) {
            KnnIndexOptions options;
            options.kernels = kernel;
            if (families) options.view_families = skewed;
            const KnnIndex index(rows, dim, options);
            for (std::size_t k : {std::size_t{1}, std::size_t{10}, k_max}) {
                const std::string what = std::string(esf::to_string(kernel)) +
                                         (families ? " families" : " views") + " k " +
                                         std::to_string(k);
                const auto one_thread = index.search_batch(queries, k, 1);
                const auto two_threads = index.search_batch(queries, k, 2);
                ASSERT_EQ(one_thread.size(), count);
                ASSERT_EQ(two_threads.size(), count);
                for (std::size_t q = 0; q < count; ++q) {
                    const std::span<const float> query(queries.data() + q * dim, dim);
                    const esf::KnnResult single = index.search(query, k);
                    const std::string at = what + " query " + std::to_string(q);
                    expect_identical(one_thread[q].neighbours, single.neighbours, at);
                    expect_identical(two_threads[q].neighbours, single.neighbours, at);
                    EXPECT_EQ(one_thread[q].exact_distances, single.exact_distances) << at;
                    const auto& all = families ? want_families[q] : want_views[q];
                    expect_same(single.neighbours,
                                {all.begin(), all.begin() + static_cast<std::ptrdiff_t>(
                                                                std::min(k, all.size()))},
                                at);
                }
            }
        }
    }
}

TEST(KnnIndex, OddDataStaysExact) {
    // Negative values, constant dimensions, queries far outside the indexed range, every
    // sketch grouping from 1 to the whole row.
    const std::size_t dim = 100, n = 500;
    std::mt19937 rng(41);
    std::uniform_real_distribution<float> value(-5.0f, 5.0f);
    std::vector<float> rows(n * dim);
    for (std::size_t r = 0; r < n; ++r)
        for (std::size_t i = 0; i < dim; ++i) rows[r * dim + i] = i < 20 ? 1.5f : value(rng);
    std::vector<float> queries(3 * dim);
    for (float& v : queries) v = value(rng);
    for (std::size_t i = 0; i < dim; ++i) queries[2 * dim + i] = 1000.0f * value(rng);
    for (int group : {0, 1, 3, 64, 100, 1000}) {
        KnnIndexOptions options;
        options.sketch_group = group;
        const KnnIndex index(rows, dim, options);
        for (std::size_t q = 0; q < 3; ++q) {
            const std::span<const float> query(queries.data() + q * dim, dim);
            expect_same(index.search(query, 10).neighbours,
                        brute_force(rows, dim, {}, query, {}, 10),
                        "group " + std::to_string(group) + " query " + std::to_string(q));
        }
    }
}

TEST(KnnIndex, IdenticalRowsTieByViewId) {
    const std::size_t dim = 640;
    std::vector<float> rows;
    for (int r = 0; r < 30; ++r) rows.insert(rows.end(), dim, 1.0f / 640.0f);
    const KnnIndex index(rows, dim);
    std::vector<float> query(dim, 0.0f);
    query[0] = 1.0f;
    const auto found = index.search(query, 10).neighbours;
    ASSERT_EQ(found.size(), 10u);
    for (std::uint32_t i = 0; i < 10; ++i) {
        EXPECT_EQ(found[i].view, i);
        EXPECT_EQ(found[i].distance, found[0].distance);
    }
}

TEST(KnnIndex, SketchExcludesMostRowsOnEsfLikeData) {
    // Not a timing test: the bound must actually exclude rows, or the index is a brute force.
    const std::size_t dim = esf::kEsfSize, n = 20000;
    const std::vector<float> rows = esf::detail::esf_like_rows(n, dim, 7, 0);
    const std::vector<float> queries = esf::detail::esf_like_rows(4, dim, 8, 1);
    const KnnIndex index(rows, dim);
    EXPECT_EQ(index.sketch_group(), 10u);
    EXPECT_EQ(index.sketch_bytes(), 64u);
    for (std::size_t q = 0; q < 4; ++q) {
        const auto found = index.search({queries.data() + q * dim, dim}, 10);
        EXPECT_LT(found.exact_distances, n / 10) << "query " << q;
    }
}

TEST(KnnIndex, MemoryPerView) {
    const std::size_t dim = esf::kEsfSize, n = 1000;
    const KnnIndex index(esf::detail::esf_like_rows(n, dim, 1, 1), dim);
    // 640 floats + 64 sketch bytes + one double of error per row, plus the weights.
    const std::size_t per_view = dim * 4 + 64 + 8;
    EXPECT_GE(index.memory_bytes(), n * per_view);
    EXPECT_LE(index.memory_bytes(), n * per_view + dim * 4 + 1024);
}

}  // namespace
}  // namespace esf::test
