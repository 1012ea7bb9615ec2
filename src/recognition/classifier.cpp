#include "esf/recognition/classifier.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

namespace esf {

void adopt_neighbour(Classification& c, const NeighbourView& n) {
    c.class_name = n.class_name;
    c.class_id = n.class_id;
    c.best_model = n.model_name;
    c.best_model_id = n.model_id;
    c.best_view = n.view;
    c.best_index = n.index;
    c.best_distance = n.distance;
    c.pose = n.pose;
}

Classification classify_neighbours(std::span<const KnnNeighbour> neighbours,
                                   std::span<const ViewLabel> labels, VoteRule rule) {
    if (neighbours.empty()) throw std::invalid_argument("classify: no neighbours to vote");
    Classification result;
    result.neighbours.reserve(neighbours.size());
    // Tally in order of first appearance, so that `first` is the rank of a class's nearest view.
    struct Tally {
        ClassVote vote;
        std::size_t first = 0;
    };
    std::vector<Tally> tallies;
    for (std::size_t rank = 0; rank < neighbours.size(); ++rank) {
        const KnnNeighbour& n = neighbours[rank];
        if (n.view >= labels.size())
            throw std::invalid_argument("classify: view " + std::to_string(n.view) +
                                        " has no label (" + std::to_string(labels.size()) +
                                        " labels)");
        const ViewLabel& label = labels[n.view];
        result.neighbours.push_back({label.class_name, label.class_id, label.model_name,
                                     label.model_id, label.view, n.view, n.distance, label.pose});
        auto it = std::find_if(tallies.begin(), tallies.end(), [&](const Tally& t) {
            return t.vote.class_name == label.class_name;
        });
        if (it == tallies.end()) {
            tallies.push_back({{label.class_name, label.class_id, 0, 0.0}, rank});
            it = tallies.end() - 1;
        }
        ++it->vote.votes;
        it->vote.distance_sum += n.distance;
    }
    // More votes first; then the smaller distance sum; then the nearer first view. The nearest
    // rule puts the nearest neighbour's class (tallies[0], first = 0) first whatever its votes.
    const auto majority_order = [](const Tally& a, const Tally& b) {
        if (a.vote.votes != b.vote.votes) return a.vote.votes > b.vote.votes;
        if (a.vote.distance_sum != b.vote.distance_sum)
            return a.vote.distance_sum < b.vote.distance_sum;
        return a.first < b.first;
    };
    if (rule == VoteRule::kNearest)
        std::sort(tallies.begin() + 1, tallies.end(), majority_order);
    else
        std::sort(tallies.begin(), tallies.end(), majority_order);
    adopt_neighbour(result, result.neighbours[tallies.front().first]);
    result.confidence =
        static_cast<double>(tallies.front().vote.votes) / static_cast<double>(neighbours.size());
    result.votes.reserve(tallies.size());
    for (Tally& t : tallies) result.votes.push_back(std::move(t.vote));
    return result;
}

Classifier::Classifier(KnnIndex index, std::vector<ViewLabel> labels,
                       const ClassifierOptions& options)
    : index_(std::move(index)), labels_(std::move(labels)), options_(options) {
    if (index_.empty()) throw std::invalid_argument("classifier: the index is empty");
    if (labels_.size() != index_.views())
        throw std::invalid_argument("classifier: " + std::to_string(labels_.size()) +
                                    " view labels for an index of " +
                                    std::to_string(index_.views()) + " views");
    if (options_.k == 0) throw std::invalid_argument("classifier: k must be >= 1");
    std::map<std::string, int> class_ids;
    for (std::size_t v = 0; v < labels_.size(); ++v) {
        const ViewLabel& label = labels_[v];
        if (label.class_name.empty())
            throw std::invalid_argument("classifier: view " + std::to_string(v) +
                                        " has no class name");
        const auto [it, inserted] = class_ids.emplace(label.class_name, label.class_id);
        if (!inserted && it->second != label.class_id)
            throw std::invalid_argument("classifier: class '" + label.class_name +
                                        "' has two ids (" + std::to_string(it->second) + " and " +
                                        std::to_string(label.class_id) + ", view " +
                                        std::to_string(v) + ")");
    }
}

Classification Classifier::classify(std::span<const float> descriptor) const {
    const KnnResult found = index_.search(descriptor, options_.k);
    return classify_neighbours(found.neighbours, labels_, options_.vote);
}

std::vector<Classification> Classifier::classify_batch(std::span<const float> descriptors,
                                                       int threads) const {
    const std::vector<KnnResult> found = index_.search_batch(descriptors, options_.k, threads);
    std::vector<Classification> results;
    results.reserve(found.size());
    for (const KnnResult& f : found)
        results.push_back(classify_neighbours(f.neighbours, labels_, options_.vote));
    return results;
}

}  // namespace esf
