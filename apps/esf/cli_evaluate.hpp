#pragma once
// Shared by esf eval and esf learn-weights: a database's descriptors for leave-one-model-out
// runs, its stored weights and the model groups of a catalog.

#include <optional>
#include <string>
#include <vector>

#include "core/number_text.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/evaluation/evaluation.hpp"
#include "esf/recognition/knn_index.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"

namespace esf::cli {

/// Per-dimension weights from a database's stored weights of `matrix.kind` (empty: none).
inline std::vector<float> stored_dimension_weights(const Database& db,
                                                   const DescriptorMatrix& matrix) {
    const std::optional<std::vector<float>> w = db.weights(matrix.kind.name);
    if (!w) return {};
    return descriptor_dimension_weights(descriptor_info(matrix.kind.name), *w);
}

/// Groups per model: from a catalog CSV when `catalog` is non-empty, else empty (one per model).
inline std::vector<std::string> cli_model_groups(const DescriptorMatrix& matrix,
                                                 const std::string& catalog) {
    if (catalog.empty()) return {};
    return model_groups(matrix, read_catalog(catalog));
}

/// Views of a matrix (consecutive rows of one model and view index are one view).
inline std::size_t view_count(const DescriptorMatrix& matrix) {
    std::size_t views = 0;
    for (std::size_t r = 0; r < matrix.rows(); ++r)
        views += r == 0 || matrix.row_info[r - 1].model != matrix.row_info[r].model ||
                 matrix.row_info[r - 1].view_index != matrix.row_info[r].view_index;
    return views;
}

/// "12.3" for a fraction 0.123.
using detail::percent_text;

}  // namespace esf::cli
