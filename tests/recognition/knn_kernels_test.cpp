// The k-nearest-neighbour kernels: every SIMD kernel bit-identical to the scalar one, and
// results that do not depend on the thread count.

#include "recognition/knn_kernels.hpp"

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
#include "support/knn_oracle.hpp"

namespace esf::test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(KnnKernels, ExactDistanceIsBitIdenticalToScalar) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> value(-1.0f, 1.0f);
    const auto scalar = esf::detail::knn_kernels(Kernels::kPortable);
    for (Kernels kernel : supported_kernels()) {
        const auto k = esf::detail::knn_kernels(kernel);
        for (std::size_t n :
             {1, 2, 7, 8, 9, 15, 16, 17, 63, 64, 65, 128, 129, 308, 352, 640, 724, 732}) {
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
    const auto scalar = esf::detail::knn_kernels(Kernels::kPortable);
    for (Kernels kernel : supported_kernels()) {
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
                std::vector<std::uint32_t> got_rows(count), want_rows(count);
                const std::uint32_t first_row = 1000;
                EXPECT_EQ(k.sketch(rows.data(), count, stride, query.data(), lane_weight.data(),
                                   unit, row_error.data(), query_error, kInf, first_row, got.data(),
                                   got_rows.data()),
                          count);
                EXPECT_EQ(scalar.sketch(rows.data(), count, stride, query.data(),
                                        lane_weight.data(), unit, row_error.data(), query_error,
                                        kInf, first_row, want.data(), want_rows.data()),
                          count);
                for (std::size_t r = 0; r < count; ++r) {
                    std::uint64_t sum = 0;  // independent of both kernels
                    for (std::size_t j = 0; j < stride; ++j)
                        sum += lane_weight[j / 8] * static_cast<std::uint64_t>(std::abs(
                                                        static_cast<int>(rows[r * stride + j]) -
                                                        static_cast<int>(query[j])));
                    EXPECT_EQ(want[r],
                              (unit * static_cast<double>(sum) - row_error[r]) - query_error);
                    EXPECT_EQ(want_rows[r], first_row + r);
                    EXPECT_EQ(got[r], want[r]) << esf::to_string(kernel) << " stride " << stride
                                               << " count " << count << " row " << r;
                    EXPECT_EQ(got_rows[r], want_rows[r]);
                }
                // With a limit (the median, and one below every bound): only the rows whose
                // bound does not exceed it, in row order.
                std::vector<double> sorted = want;
                std::sort(sorted.begin(), sorted.end());
                for (const double limit : {sorted[count / 2], sorted.front() - 1.0}) {
                    std::vector<double> kept_bounds;
                    std::vector<std::uint32_t> kept_rows;
                    for (std::size_t r = 0; r < count; ++r) {
                        if (want[r] > limit) continue;
                        kept_bounds.push_back(want[r]);
                        kept_rows.push_back(first_row + static_cast<std::uint32_t>(r));
                    }
                    std::vector<double> below(count);
                    std::vector<std::uint32_t> below_rows(count);
                    const std::size_t kept =
                        k.sketch(rows.data(), count, stride, query.data(), lane_weight.data(), unit,
                                 row_error.data(), query_error, limit, first_row, below.data(),
                                 below_rows.data());
                    below.resize(kept);
                    below_rows.resize(kept);
                    EXPECT_EQ(below, kept_bounds) << esf::to_string(kernel) << " limit " << limit;
                    EXPECT_EQ(below_rows, kept_rows);
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
    options.kernels = Kernels::kPortable;
    const KnnIndex reference(rows, dim, options);
    const auto want = reference.search_batch(queries, 20, 1);
    for (Kernels kernel : supported_kernels()) {
        options.kernels = kernel;
        const KnnIndex index(rows, dim, options);
        EXPECT_EQ(index.kernels(), kernel);
        const auto got = index.search_batch(queries, 20, 1);
        ASSERT_EQ(got.size(), want.size());
        for (std::size_t q = 0; q < got.size(); ++q)
            expect_identical(got[q].neighbours, want[q].neighbours, esf::to_string(kernel));
    }
}

TEST(KnnKernels, BestPicksSupportedKernels) {
    EXPECT_TRUE(esf::kernels_supported(Kernels::kBest));
    EXPECT_TRUE(esf::kernels_supported(Kernels::kPortable));
    EXPECT_TRUE(esf::kernels_supported(esf::best_kernels()));
    EXPECT_NE(esf::best_kernels(), Kernels::kBest);
    const KnnIndex index(std::vector<float>{1.0f, 2.0f}, 1);
    EXPECT_EQ(index.kernels(), esf::best_kernels());
    EXPECT_STREQ(esf::to_string(Kernels::kAvx512), "avx512");
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

}  // namespace
}  // namespace esf::test
