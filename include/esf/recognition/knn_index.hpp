#pragma once
// Exact k-nearest-neighbour search by (weighted) L1 distance over descriptors of any dimension:
// ESF (640), VFH (308), SHOT (352), D2 only (64), ...
//
//     distance(a, b) = sum_i w_i |a_i - b_i|        (w_i = 1 without weights)
//
// Results equal brute force: the same views, in the same order, with the same distances; ties
// are broken by view id (lower first). The search is the optimal multi-step k-NN search of Seidl
// & Kriegel ("Optimal multi-step k-nearest neighbor search", SIGMOD 1998) with a provable lower
// bound from an 8-bit sketch:
//
//  1. Sketch. Each row is summarised by sums of its weighted values w_i x_i over `group`
//     consecutive dimensions (64 sums or fewer: 10 bins per sum for ESF), quantised to 8 bits
//     with an offset and a step per lane of 8 sums. By the triangle inequality the L1 distance
//     between two sketches never exceeds the true distance, and the distance between the
//     dequantised sketches (a sum of SAD instructions, 64 bytes each, with an integer weight
//     per lane) is off from it by at most the two stored quantisation errors:
//         lower_bound(row) = sketch_distance - error(row) - error(query) <= distance.
//     The bound is lowered by a relative 1e-9 and an absolute 1e-12 of the values' magnitude,
//     more than every floating-point rounding involved, so it holds exactly, not just nearly.
//  2. Refine. The exact distances (accumulated in double) of the rows with the smallest bounds
//     set the k-th distance; then every other row whose bound does not exceed the k-th distance
//     gets its exact distance, in increasing bound order, until the next bound exceeds it. Only
//     rows that cannot be among the k nearest are skipped. For ESF-like data about 150 of
//     300,000 rows need an exact distance for k = 10.
//
// No bound is stored: the bounds of a sample of the rows (4,096 of them, at most one in 8) set
// a cut (a small rank of them), and one pass over the sketches keeps only the rows whose bound
// falls under it (about 4 * k * rows / 4096 of them: 3,000 of 300,000 for k = 10), enough for
// both steps unless the k-th distance lies beyond the cut; then a second pass collects the rows
// under the k-th distance. A batch shares each pass among up to 16 queries, so the sketches are
// read from memory once for all of them.
//
// Exact distances are accumulated in double in a fixed order (eight lanes, lane i % 8, combined
// pairwise), which every kernel (portable, AVX2, AVX-512) reproduces bit for bit; the sketch
// bounds are integer sums, also bit-identical. Results do not depend on the CPU or the number of
// threads. Kernels are chosen at run time from what the CPU supports (no -march flags needed);
// KnnIndexOptions::kernels forces a set (for tests and benchmarks).
//
// Groups: several rows may belong to one view (e.g. the CVFH signatures of a view); a view's
// distance is then the minimum over its rows, as in PCL's recognition pipeline, and the results
// are views, each reported with the row that attained the minimum.
//
// Families: views may also belong to families (e.g. the models of a database, whose views are
// alike); a search with families returns at most one view per family, its nearest, so the k
// results are the k nearest families, each by its nearest view and row.
//
// Memory per view (one row each): 4 * dimension bytes (the float row) + the sketch (64 bytes for
// any dimension up to 4096 with the default group) + 8 bytes (its quantisation error): 2,632
// bytes for ESF; + 4 bytes per row with groups. A search allocates little besides: the rows
// under its cut (16 bytes each; about 10,000 at 1 million rows for k = 10), a copy of the
// sample's sketches (at most 4,096 rows: 300 KB for ESF), and 16 bytes per row when groups or
// families leave the first rows short of k views or families.
//
// Thread safety: a built index is immutable; search() and search_batch() are const and may run
// concurrently from any number of threads.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "esf/core/kernels.hpp"

namespace esf {

struct KnnIndexOptions {
    /// Per-dimension weights w_i (finite, >= 0), one per dimension; empty = all 1. For ESF's ten
    /// sub-histogram weights use expand_block_weights(block_weights, kEsfBins).
    std::vector<float> weights;
    /// Dimensions summed into one sketch value; 0 = ceil(dimension / 64). 1 = a full 8-bit copy
    /// of every row (the tightest bound, but `dimension` bytes per row to scan).
    int sketch_group = 0;
    /// The distance kernels: kBest the widest the CPU runs (best_kernels()); another set must
    /// be supported by the CPU (kernels_supported()).
    Kernels kernels = Kernels::kBest;
    /// Family of each view (one per view; numbered 0 .. F-1 without gaps); empty = none. A
    /// search then returns at most one view per family (see the header).
    std::vector<std::uint32_t> view_families;
    /// Threads used while building (0 = all cores).
    int threads = 0;
};

/// One neighbour: a view, its distance, and the row that attained it (the lowest-numbered row
/// of the view among those at the minimum; equal to `view` without groups).
struct KnnNeighbour {
    std::uint32_t view = 0;
    std::uint32_t row = 0;
    double distance = 0.0;
};

/// Neighbours sorted by (distance, view); `exact_distances` counts the rows whose exact
/// distance was computed (the rest were excluded by their lower bound).
struct KnnResult {
    std::vector<KnnNeighbour> neighbours;
    std::size_t exact_distances = 0;
};

/// Expands per-block weights to per-dimension weights: block_weights[b] for each of the
/// `bins_per_block` dimensions of block b (ESF: ten blocks of 64 bins).
std::vector<float> expand_block_weights(std::span<const float> block_weights,
                                        std::size_t bins_per_block);

class KnnIndex {
  public:
    /// An empty index (searching it throws).
    KnnIndex() = default;

    /// Indexes `rows` (row-major, rows.size() / dimension rows, copied), one view per row.
    /// Throws std::invalid_argument for dimension 0, a size that is not a multiple of the
    /// dimension, non-finite values, bad weights or an unsupported kernel.
    KnnIndex(std::span<const float> rows, std::size_t dimension,
             const KnnIndexOptions& options = {});

    /// As above with groups: row r belongs to view row_views[r]. The views are 0 .. V-1 and
    /// each of them must have at least one row.
    KnnIndex(std::span<const float> rows, std::size_t dimension,
             std::span<const std::uint32_t> row_views, const KnnIndexOptions& options = {});

    /// The k nearest views (fewer when the index has fewer views), with families the nearest
    /// view of each of the k nearest families (fewer when it has fewer). Throws
    /// std::invalid_argument for an empty index, k = 0, a query of the wrong dimension or with
    /// non-finite values.
    KnnResult search(std::span<const float> query, std::size_t k) const;

    /// Searches queries.size() / dimension() queries (row-major) on `threads` threads
    /// (0 = all cores); the results do not depend on the thread count.
    std::vector<KnnResult> search_batch(std::span<const float> queries, std::size_t k,
                                        int threads = 0) const;

    /// The exact distance between `query` and row `row`, as search() computes it.
    double distance(std::span<const float> query, std::size_t row) const;

    std::size_t dimension() const { return dimension_; }
    std::size_t rows() const { return rows_; }
    std::size_t views() const { return views_; }
    bool empty() const { return rows_ == 0; }
    bool grouped() const { return !row_views_.empty(); }
    /// View of row `row`.
    std::uint32_t view_of(std::size_t row) const {
        return row_views_.empty() ? static_cast<std::uint32_t>(row) : row_views_[row];
    }
    /// Families (0 without).
    std::size_t families() const { return families_; }
    bool has_families() const { return !view_families_.empty(); }
    /// Family of view `view` (the view itself without families).
    std::uint32_t family_of(std::uint32_t view) const {
        return view_families_.empty() ? view : view_families_[view];
    }
    std::span<const float> row(std::size_t row) const {
        return {data_.data() + row * dimension_, dimension_};
    }
    /// Per-dimension weights in use (all 1 when unweighted).
    std::span<const float> weights() const { return weights_; }
    /// The kernels in use (never kBest).
    Kernels kernels() const { return kernels_; }
    /// Dimensions per sketch value, and bytes of sketch per row.
    std::size_t sketch_group() const { return group_; }
    std::size_t sketch_bytes() const { return stride_; }
    /// Bytes held by the index (rows, sketches, errors, groups, weights).
    std::size_t memory_bytes() const;

  private:
    void build(std::span<const float> rows, std::size_t dimension,
               std::span<const std::uint32_t> row_views, bool grouped,
               const KnnIndexOptions& options);
    void check_query(std::span<const float> query, const std::string& what) const;
    double quantise_sketch(std::span<const double> values, double magnitude,
                           std::uint8_t* codes) const;
    /// A row and its lower bound for one query: (lower bound, row).
    using Candidate = std::pair<double, std::uint32_t>;
    /// Sketch codes (sketch_bytes() each) and quantisation errors of the queries.
    void sketch_queries(std::span<const float> queries, std::uint8_t* codes, double* errors) const;
    /// One pass over the sketches for `count` queries: appends to candidates[q] every row whose
    /// lower bound for query q (codes + q * sketch_bytes(), errors[q]) does not exceed limits[q]
    /// and whose (bound, row) comes after after[q], in row order.
    void collect_candidates(std::size_t count, const std::uint8_t* codes, const double* errors,
                            const double* limits, const Candidate* after,
                            std::vector<Candidate>* candidates) const;
    /// The number of results of a search for k: k, or fewer views or families.
    std::size_t wanted(std::size_t k) const;
    /// The rows refined first (those with the smallest bounds) for `want` results.
    std::size_t seed_count(std::size_t want) const;
    KnnResult search_checked(std::span<const float> query, std::size_t k) const;
    /// Searches queries.size() / dimension() checked queries, sharing the passes over the
    /// sketches that find their candidates; results[q] is query q's.
    void search_group(std::span<const float> queries, std::size_t k, KnnResult* results) const;
    /// Starts fetching row `row` into the cache.
    void prefetch_row(std::size_t row) const;
    /// Lower bounds of every row for `count` queries, one pass: bounds[q * rows + r].
    void all_bounds(std::size_t count, const std::uint8_t* codes, const double* errors,
                    double* bounds) const;
    /// The search of one query (sketch `codes`, quantisation error `error`) given the rows
    /// whose bounds do not exceed `cut`, at least seed_count() of them (reordered as it goes).
    /// `stored`: every row's bound for the query (all_bounds()), read instead of passing over
    /// the sketches again; null: passes over them.
    KnnResult search_bounded(std::span<const float> query, std::size_t k, const std::uint8_t* codes,
                             double error, double cut, std::vector<Candidate>& below_cut,
                             const double* stored) const;

    std::size_t dimension_ = 0;
    std::size_t rows_ = 0;
    std::size_t views_ = 0;
    std::size_t families_ = 0;
    std::vector<std::uint32_t> view_families_;
    std::vector<float> data_;
    std::vector<float> weights_;
    std::vector<std::uint32_t> row_views_;
    Kernels kernels_ = Kernels::kPortable;
    std::size_t group_ = 1;
    std::size_t sketch_values_ = 0;  // sums per row before padding
    std::size_t stride_ = 0;         // sketch bytes per row (multiple of 16)
    std::vector<std::uint8_t> sketch_;
    std::vector<double> row_error_;           // per row: bound on |sketch - dequantised sketch|_1
    std::vector<double> lane_offset_;         // per 8-byte lane: value of code 0
    std::vector<double> lane_scale_;          // per lane: value step of one code
    std::vector<std::uint32_t> lane_weight_;  // per lane: integer weight of the bound
    double sketch_unit_ = 0.0;                // value of one unit of weight * SAD
};

}  // namespace esf
