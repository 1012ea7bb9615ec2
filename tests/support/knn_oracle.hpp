#pragma once
// The k-nearest-neighbour tests' oracle and data: brute force in double, result comparisons,
// the kernels this CPU runs, ESF-like rows with duplicates and queries that tie.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "esf/recognition/knn_index.hpp"
#include "recognition/knn_synthetic.hpp"

namespace esf::test {

using esf::Kernels;
using esf::KnnNeighbour;

/// Brute force in double: distance = sum_i w_i |q_i - x_i| summed in index order; a view's
/// distance is the minimum over its rows (lowest row first); sorted by (distance, view).
inline std::vector<KnnNeighbour> brute_force(const std::vector<float>& rows, std::size_t dim,
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
inline void expect_same(const std::vector<KnnNeighbour>& got, const std::vector<KnnNeighbour>& want,
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
inline void expect_identical(const std::vector<KnnNeighbour>& a, const std::vector<KnnNeighbour>& b,
                             const std::string& what) {
    ASSERT_EQ(a.size(), b.size()) << what;
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].view, b[i].view) << what << " rank " << i;
        EXPECT_EQ(a[i].row, b[i].row) << what << " rank " << i;
        EXPECT_EQ(a[i].distance, b[i].distance) << what << " rank " << i;
    }
}

inline std::vector<Kernels> supported_kernels() {
    std::vector<Kernels> kernels;
    for (Kernels k : {Kernels::kPortable, Kernels::kAvx2, Kernels::kAvx512})
        if (esf::kernels_supported(k)) kernels.push_back(k);
    return kernels;
}

/// ESF-like rows with exact duplicates: every 7th row repeats an earlier one.
inline std::vector<float> rows_with_duplicates(std::size_t n, std::size_t dim, std::uint64_t seed) {
    std::vector<float> rows = esf::detail::esf_like_rows(n, dim, seed, 1);
    for (std::size_t r = 7; r < n; r += 7)
        std::copy_n(rows.begin() + static_cast<std::ptrdiff_t>((r / 3) * dim), dim,
                    rows.begin() + static_cast<std::ptrdiff_t>(r * dim));
    return rows;
}

/// Queries: fresh random rows, exact copies of duplicated rows (distance 0, tied), and rows
/// with a little noise.
inline std::vector<float> make_queries(const std::vector<float>& rows, std::size_t dim,
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

}  // namespace esf::test
