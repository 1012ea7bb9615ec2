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
// bytes for ESF; + 4 bytes per row with groups. A search also allocates 8 bytes per row for the
// bounds while it runs.
//
// Thread safety: a built index is immutable; search() and search_batch() are const and may run
// concurrently from any number of threads.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
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
    KnnResult search_checked(std::span<const float> query, std::size_t k) const;
    /// Lower bounds of every row's distance to each of queries.size() / dimension() queries:
    /// bounds[q * rows() + r].
    void lower_bounds(std::span<const float> queries, double* bounds) const;
    /// The search of one query given its rows' lower bounds (overwritten as it goes).
    KnnResult search_bounded(std::span<const float> query, std::size_t k, double* bound) const;

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
