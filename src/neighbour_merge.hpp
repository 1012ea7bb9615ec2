#pragma once
// Internal: k-NN lists of views that have several signatures (CVFH, OUR-CVFH), merged into one.

#include <algorithm>
#include <cstddef>
#include <vector>

#include "esf/knn_index.hpp"

namespace esf::detail {

/// Merges per-signature neighbour lists: a view's distance is its minimum (ties: lower row);
/// views for which `keep` is false are dropped; the k nearest by (distance, view) remain.
template <typename Keep>
std::vector<KnnNeighbour> merge_signature_neighbours(std::vector<KnnNeighbour> all, std::size_t k,
                                                     Keep keep) {
    std::sort(all.begin(), all.end(), [](const KnnNeighbour& a, const KnnNeighbour& b) {
        if (a.view != b.view) return a.view < b.view;
        if (a.distance != b.distance) return a.distance < b.distance;
        return a.row < b.row;
    });
    std::vector<KnnNeighbour> best;
    for (const KnnNeighbour& n : all)
        if ((best.empty() || best.back().view != n.view) && keep(n.view)) best.push_back(n);
    std::sort(best.begin(), best.end(), [](const KnnNeighbour& a, const KnnNeighbour& b) {
        if (a.distance != b.distance) return a.distance < b.distance;
        return a.view < b.view;
    });
    if (best.size() > k) best.resize(k);
    return best;
}

}  // namespace esf::detail
