#pragma once
// Internal: the exact leave-one-group-out search shared by evaluate_synthetic() and
// learn_weights(). Views are (model, view index) pairs of a DescriptorMatrix; consecutive rows
// of a view are its signatures.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "esf/recognition/knn_index.hpp"
#include "esf/training/database.hpp"
#include "recognition/neighbour_merge.hpp"

namespace esf::detail {

struct LomoSetup {
    std::vector<std::uint32_t> row_views;      ///< view of each matrix row
    std::vector<std::size_t> view_first_row;   ///< views + 1 offsets into the rows
    std::vector<std::uint32_t> view_category;  ///< category of each view
    std::vector<std::uint32_t> view_group;     ///< group id of each view
    std::vector<std::uint32_t> view_model;     ///< model of each view, numbered 0 .. M-1
    std::vector<std::size_t> group_views;      ///< views per group id
    bool multi_signature = false;              ///< some view has several rows
    /// The rows after a view's first are occluded copies (training's `occlusions`, a descriptor
    /// of one signature a cloud): a view queries with its first row, its own signature.
    bool occluded_copies = false;

    std::size_t views() const { return view_category.size(); }
};

/// Views and groups of `matrix`; `groups` one name per model (empty: one group per model).
/// Throws std::invalid_argument for a matrix without rows, a groups vector of the wrong size or
/// fewer than two groups (`what` prefixes the messages).
LomoSetup lomo_setup(const DescriptorMatrix& matrix, const std::vector<std::string>& groups,
                     const std::string& what);

/// Whether row `r` of `matrix` is another signature of the view of row r - 1.
inline bool continues_view(const DescriptorMatrix& matrix, std::size_t r) {
    return r > 0 && matrix.row_info[r - 1].model == matrix.row_info[r].model &&
           matrix.row_info[r - 1].view_index == matrix.row_info[r].view_index;
}

/// Whether some view of `matrix` holds occluded copies after its own signature: it holds
/// several rows, and the matrix's descriptor gives one signature a cloud.
bool has_occluded_copies(const DescriptorMatrix& matrix);

/// `matrix` with the first row of each view alone (its own signature, the copies dropped).
DescriptorMatrix own_view_signatures(const DescriptorMatrix& matrix);

/// Query views: all (max_queries = 0 or >= views) or floor(i * views / max_queries).
std::vector<std::size_t> lomo_queries(std::size_t views, std::size_t max_queries);

/// One index over every row of `matrix`, grouped by view when views have several rows; with
/// `per_model` its searches return one view per model (KnnIndexOptions::view_families).
KnnIndex lomo_index(const DescriptorMatrix& matrix, const LomoSetup& setup,
                    std::vector<float> weights, int threads, bool per_model);

/// The k nearest views of view `query` among the views of the other groups, by (distance, view):
/// exactly brute force. A multi-signature view's distance is the minimum over signature pairs
/// (over the rows of the view found, its first row alone querying, with occluded copies).
std::vector<KnnNeighbour> lomo_search(const KnnIndex& index, const LomoSetup& setup,
                                      std::size_t query, std::size_t k);

// ---- implementation -------------------------------------------------------------------------

}  // namespace esf::detail
