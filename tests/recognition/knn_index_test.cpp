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
#include "recognition/knn_synthetic.hpp"
#include "support/error_of.hpp"
#include "support/test_data.hpp"

namespace {

using esf::KnnIndex;
using esf::KnnIndexOptions;
using esf::KnnKernel;
using esf::KnnNeighbour;

/// Brute force in double: distance = sum_i w_i |q_i - x_i| summed in index order; a view's
/// distance is the minimum over its rows (lowest row first); sorted by (distance, view).
std::vector<KnnNeighbour> brute_force(const std::vector<float>& rows, std::size_t dim,
                                      const std::vector<std::uint32_t>& row_views,
                                      std::span<const float> query,
                                      const std::vector<float>& weights, std::size_t k) {
    const std::size_t n = rows.size() / dim;
    std::vector<KnnNeighbour> best;
    for (std::size_t r = 0; r < n; ++r) {
        double d = 0.0;
        for (std::size_t i = 0; i < dim; ++i) {
            const double w = weights.empty() ? 1.0 : static_cast<double>(weights[i]);
            d += w *
                 std::fabs(static_cast<double>(query[i]) - static_cast<double>(rows[r * dim + i]));
        }
        const std::uint32_t view = row_views.empty() ? static_cast<std::uint32_t>(r) : row_views[r];
        auto it = std::find_if(best.begin(), best.end(),
                               [&](const KnnNeighbour& b) { return b.view == view; });
        if (it == best.end())
            best.push_back({view, static_cast<std::uint32_t>(r), d});
        else if (d < it->distance)
            *it = {view, static_cast<std::uint32_t>(r), d};
    }
    std::sort(best.begin(), best.end(), [](const KnnNeighbour& a, const KnnNeighbour& b) {
        return a.distance < b.distance || (a.distance == b.distance && a.view < b.view);
    });
    best.resize(std::min(k, best.size()));
    return best;
}

/// Same views and rows in the same order, distances equal to rounding.
void expect_same(const std::vector<KnnNeighbour>& got, const std::vector<KnnNeighbour>& want,
                 const std::string& what) {
    ASSERT_EQ(got.size(), want.size()) << what;
    for (std::size_t i = 0; i < want.size(); ++i) {
        EXPECT_EQ(got[i].view, want[i].view) << what << " rank " << i;
        EXPECT_EQ(got[i].row, want[i].row) << what << " rank " << i;
        EXPECT_NEAR(got[i].distance, want[i].distance, 1e-12 * std::max(1.0, want[i].distance))
            << what << " rank " << i;
    }
}

/// Bitwise-identical results.
void expect_identical(const std::vector<KnnNeighbour>& a, const std::vector<KnnNeighbour>& b,
                      const std::string& what) {
    ASSERT_EQ(a.size(), b.size()) << what;
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].view, b[i].view) << what << " rank " << i;
        EXPECT_EQ(a[i].row, b[i].row) << what << " rank " << i;
        EXPECT_EQ(a[i].distance, b[i].distance) << what << " rank " << i;
    }
}

std::vector<KnnKernel> supported_kernels() {
    std::vector<KnnKernel> kernels;
    for (KnnKernel k : {KnnKernel::kScalar, KnnKernel::kAvx2, KnnKernel::kAvx512})
        if (esf::knn_kernel_supported(k)) kernels.push_back(k);
    return kernels;
}

/// ESF-like rows with exact duplicates: every 7th row repeats an earlier one.
std::vector<float> rows_with_duplicates(std::size_t n, std::size_t dim, std::uint64_t seed) {
    std::vector<float> rows = esf::detail::esf_like_rows(n, dim, seed, 1);
    for (std::size_t r = 7; r < n; r += 7)
        std::copy_n(rows.begin() + static_cast<std::ptrdiff_t>((r / 3) * dim), dim,
                    rows.begin() + static_cast<std::ptrdiff_t>(r * dim));
    return rows;
}

/// Queries: fresh random rows, exact copies of duplicated rows (distance 0, tied), and rows
/// with a little noise.
std::vector<float> make_queries(const std::vector<float>& rows, std::size_t dim,
                                std::uint64_t seed) {
    std::vector<float> queries = esf::detail::esf_like_rows(6, dim, seed + 1000, 1);
    std::mt19937 rng(static_cast<std::uint32_t>(seed));
    const std::size_t n = rows.size() / dim;
    for (std::size_t r : {std::size_t{7}, std::size_t{14}, (n / 2) / 7 * 7})
        queries.insert(queries.end(), rows.begin() + static_cast<std::ptrdiff_t>(r * dim),
                       rows.begin() + static_cast<std::ptrdiff_t>((r + 1) * dim));
    std::uniform_real_distribution<float> noise(-2e-4f, 2e-4f);
    for (std::size_t r : {std::size_t{3}, n - 1}) {
        for (std::size_t i = 0; i < dim; ++i)
            queries.push_back(std::max(0.0f, rows[r * dim + i] + noise(rng)));
    }
    return queries;
}

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
    for (KnnKernel kernel : supported_kernels()) {
        options.kernel = kernel;
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
    for (KnnKernel kernel : supported_kernels()) {
        KnnIndexOptions options;
        options.kernel = kernel;
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
    for (KnnKernel kernel : supported_kernels()) {
        KnnIndexOptions options;
        options.kernel = kernel;
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
    for (KnnKernel kernel : supported_kernels()) {
        for (const int layout : {0, 1, 2}) {
            const bool grouped = layout == 1;
            KnnIndexOptions options;
            options.kernel = kernel;
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

TEST(KnnKernels, ExactDistanceIsBitIdenticalToScalar) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> value(-1.0f, 1.0f);
    const auto scalar = esf::detail::knn_kernels(KnnKernel::kScalar);
    for (KnnKernel kernel : supported_kernels()) {
        const auto k = esf::detail::knn_kernels(kernel);
        for (std::size_t n :
             {1, 2, 7, 8, 9, 15, 16, 17, 63, 64, 65, 128, 129, 308, 352, 640, 724}) {
            std::vector<float> a(n), b(n), w(n);
            for (std::size_t i = 0; i < n; ++i) {
                a[i] = value(rng);
                b[i] = value(rng);
                w[i] = std::fabs(value(rng));
            }
            const double inf = std::numeric_limits<double>::infinity();
            const double want = scalar.exact(a.data(), b.data(), w.data(), n, inf);
            EXPECT_EQ(k.exact(a.data(), b.data(), w.data(), n, inf), want)
                << esf::to_string(kernel) << " n " << n;
            // A limit at or above the distance changes nothing; below it, the kernel may stop
            // early, and whatever it returns then lies above the limit.
            EXPECT_EQ(k.exact(a.data(), b.data(), w.data(), n, want), want)
                << esf::to_string(kernel) << " n " << n;
            for (const double limit : {0.0, want / 4, want / 2, std::nextafter(want, 0.0)})
                EXPECT_GT(k.exact(a.data(), b.data(), w.data(), n, limit), limit)
                    << esf::to_string(kernel) << " n " << n << " limit " << limit;
            double naive = 0.0;
            for (std::size_t i = 0; i < n; ++i)
                naive += static_cast<double>(w[i]) *
                         std::fabs(static_cast<double>(a[i]) - static_cast<double>(b[i]));
            EXPECT_NEAR(want, naive, 1e-13 * static_cast<double>(n));
        }
    }
}

TEST(KnnKernels, SketchBoundIsBitIdenticalToScalar) {
    std::mt19937 rng(6);
    std::uniform_int_distribution<int> byte(0, 255);
    std::uniform_int_distribution<std::uint32_t> weight(0, 65535);
    std::uniform_real_distribution<double> error(0.0, 1e-3);
    const auto scalar = esf::detail::knn_kernels(KnnKernel::kScalar);
    for (KnnKernel kernel : supported_kernels()) {
        const auto k = esf::detail::knn_kernels(kernel);
        for (std::size_t stride : {16, 32, 48, 64, 80, 96, 128, 640}) {
            for (std::size_t count : {1, 7, 8, 37}) {  // whole groups of 4 and 8 and the rest
                std::vector<std::uint8_t> rows(count * stride), query(stride);
                for (auto& v : rows) v = static_cast<std::uint8_t>(byte(rng));
                for (auto& v : query) v = static_cast<std::uint8_t>(byte(rng));
                std::vector<std::uint32_t> lane_weight((stride / 8 + 7) / 8 * 8, 0);
                for (std::size_t l = 0; l < stride / 8; ++l) lane_weight[l] = weight(rng);
                std::vector<double> row_error(count);
                for (double& e : row_error) e = error(rng);
                const double unit = 3.7e-9, query_error = 2.5e-4;
                std::vector<double> got(count), want(count);
                k.sketch(rows.data(), count, stride, query.data(), lane_weight.data(), unit,
                         row_error.data(), query_error, got.data());
                scalar.sketch(rows.data(), count, stride, query.data(), lane_weight.data(), unit,
                              row_error.data(), query_error, want.data());
                for (std::size_t r = 0; r < count; ++r) {
                    std::uint64_t sum = 0;  // independent of both kernels
                    for (std::size_t j = 0; j < stride; ++j)
                        sum += lane_weight[j / 8] * static_cast<std::uint64_t>(std::abs(
                                                        static_cast<int>(rows[r * stride + j]) -
                                                        static_cast<int>(query[j])));
                    EXPECT_EQ(want[r],
                              (unit * static_cast<double>(sum) - row_error[r]) - query_error);
                    EXPECT_EQ(got[r], want[r]) << esf::to_string(kernel) << " stride " << stride
                                               << " count " << count << " row " << r;
                }
            }
        }
    }
}

TEST(KnnKernels, EveryKernelGivesIdenticalResults) {
    const std::size_t dim = 640, n = 3000;
    const std::vector<float> rows = rows_with_duplicates(n, dim, 2);
    const std::vector<float> queries = make_queries(rows, dim, 3);
    KnnIndexOptions options;
    options.kernel = KnnKernel::kScalar;
    const KnnIndex reference(rows, dim, options);
    const auto want = reference.search_batch(queries, 20, 1);
    for (KnnKernel kernel : supported_kernels()) {
        options.kernel = kernel;
        const KnnIndex index(rows, dim, options);
        EXPECT_EQ(index.kernel(), kernel);
        const auto got = index.search_batch(queries, 20, 1);
        ASSERT_EQ(got.size(), want.size());
        for (std::size_t q = 0; q < got.size(); ++q)
            expect_identical(got[q].neighbours, want[q].neighbours, esf::to_string(kernel));
    }
}

TEST(KnnKernels, AutoPicksASupportedKernel) {
    EXPECT_TRUE(esf::knn_kernel_supported(KnnKernel::kAuto));
    EXPECT_TRUE(esf::knn_kernel_supported(KnnKernel::kScalar));
    EXPECT_TRUE(esf::knn_kernel_supported(esf::knn_best_kernel()));
    EXPECT_NE(esf::knn_best_kernel(), KnnKernel::kAuto);
    const KnnIndex index(std::vector<float>{1.0f, 2.0f}, 1);
    EXPECT_EQ(index.kernel(), esf::knn_best_kernel());
    EXPECT_STREQ(esf::to_string(KnnKernel::kAvx512), "avx512");
}

TEST(KnnIndex, BatchIsIdenticalForOneAndTwoThreads) {
    const std::size_t dim = 352, n = 2500;
    const std::vector<float> rows = rows_with_duplicates(n, dim, 9);
    const std::vector<float> queries = esf::detail::esf_like_rows(24, dim, 10, 1);
    const KnnIndex index(rows, dim);
    const auto one = index.search_batch(queries, 10, 1);
    const auto two = index.search_batch(queries, 10, 2);
    ASSERT_EQ(one.size(), 24u);
    ASSERT_EQ(two.size(), 24u);
    for (std::size_t q = 0; q < one.size(); ++q) {
        expect_identical(one[q].neighbours, two[q].neighbours, "query " + std::to_string(q));
        EXPECT_EQ(one[q].exact_distances, two[q].exact_distances);
        expect_identical(index.search({queries.data() + q * dim, dim}, 10).neighbours,
                         one[q].neighbours, "single query " + std::to_string(q));
    }
    EXPECT_TRUE(index.search_batch(std::span<const float>(), 10).empty());
}

TEST(KnnIndex, BuildIsIdenticalForOneAndTwoThreads) {
    const std::size_t dim = 640, n = 3000;
    const std::vector<float> rows = esf::detail::esf_like_rows(n, dim, 12, 2);
    EXPECT_EQ(rows, esf::detail::esf_like_rows(n, dim, 12, 1));
    KnnIndexOptions one;
    one.threads = 1;
    KnnIndexOptions two;
    two.threads = 2;
    const KnnIndex a(rows, dim, one);
    const KnnIndex b(rows, dim, two);
    const std::vector<float> queries = esf::detail::esf_like_rows(5, dim, 13, 1);
    for (std::size_t q = 0; q < 5; ++q) {
        const auto ra = a.search({queries.data() + q * dim, dim}, 10);
        const auto rb = b.search({queries.data() + q * dim, dim}, 10);
        expect_identical(ra.neighbours, rb.neighbours, "query " + std::to_string(q));
        EXPECT_EQ(ra.exact_distances, rb.exact_distances);
    }
}

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
    for (KnnKernel kernel : {KnnKernel::kAvx2, KnnKernel::kAvx512}) {
        if (esf::knn_kernel_supported(kernel)) continue;
        options.threads = 0;
        options.kernel = kernel;
        EXPECT_EQ(error_of([&] { KnnIndex(rows, 2, options); }),
                  std::string("knn index: kernel ") + esf::to_string(kernel) +
                      " is not supported by this CPU");
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
