#pragma once
// Internal: k-NN lists of views that have several signatures (CVFH, OUR-CVFH), merged into one.

#include <algorithm>
#include <cstddef>
#include <vector>

#include "esf/recognition/knn_index.hpp"

namespace esf::detail {

/// Merges per-signature neighbour lists: a view's distance is its minimum (ties: lower row);
/// views for which `keep` is false are dropped; with an index of families (KnnIndex) a family
/// keeps only its nearest view; the k nearest by (distance, view) remain.
template <typename Keep>
std::vector<KnnNeighbour> merge_signature_neighbours(std::vector<KnnNeighbour> all, std::size_t k,
                                                     const KnnIndex& index, Keep keep) {
    const auto key = [&](const KnnNeighbour& n) { return index.family_of(n.view); };
    std::sort(all.begin(), all.end(), [&](const KnnNeighbour& a, const KnnNeighbour& b) {
        if (key(a) != key(b)) return key(a) < key(b);
        if (a.distance != b.distance) return a.distance < b.distance;
        if (a.view != b.view) return a.view < b.view;
        return a.row < b.row;
    });
    std::vector<KnnNeighbour> best;
    for (const KnnNeighbour& n : all)
        if ((best.empty() || key(best.back()) != key(n)) && keep(n.view)) best.push_back(n);
    std::sort(best.begin(), best.end(), [](const KnnNeighbour& a, const KnnNeighbour& b) {
        if (a.distance != b.distance) return a.distance < b.distance;
        return a.view < b.view;
    });
    if (best.size() > k) best.resize(k);
    return best;
}

}  // namespace esf::detail
