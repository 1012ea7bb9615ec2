#pragma once
// Classification by voting over the k nearest database views (Wohlkinger & Vincze 2011,
// Sec. IV: the class of the nearest training views by L1 distance).
//
// Each of the k nearest views casts one vote for its class. The class with the most votes wins;
// equal vote counts go to the smaller sum of the voters' distances, then to the class of the
// nearer neighbour. k = 1 gives the class of the nearest view. The confidence is the winner's
// share of the votes; the best model, view and pose are those of the nearest view of the
// winning class.
//
// The classifier holds a KnnIndex and one ViewLabel per index view, all in memory; it does not
// care where they came from (a database, a test, another descriptor). Thread safety: classify()
// and classify_batch() are const and may run concurrently.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "esf/knn_index.hpp"

namespace esf {

/// What is known about one view of the index (view id = position in the label list).
struct ViewLabel {
    std::string class_name;
    int class_id = -1;  ///< optional; must agree for equal class names
    std::string model_name;
    int model_id = -1;  ///< optional
    int view = 0;       ///< number of the view within its model
    /// Pose of the view, passed through as given (esf's database stores model -> camera).
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
};

struct ClassifierOptions {
    std::size_t k = 10;  ///< views that vote (fewer when the index has fewer views)
};

/// One of the k nearest views, with its labels.
struct NeighbourView {
    std::string class_name;
    int class_id = -1;
    std::string model_name;
    int model_id = -1;
    int view = 0;
    std::uint32_t index = 0;  ///< view id in the index
    double distance = 0.0;
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
};

/// Votes of one class among the k nearest views.
struct ClassVote {
    std::string class_name;
    int class_id = -1;
    std::size_t votes = 0;
    double distance_sum = 0.0;
};

struct Classification {
    std::string class_name;
    int class_id = -1;
    double confidence = 0.0;  ///< share of the votes, in (0, 1]
    std::string best_model;   ///< model of the nearest view of the winning class
    int best_model_id = -1;
    int best_view = 0;
    std::uint32_t best_index = 0;  ///< its view id in the index
    double best_distance = 0.0;
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();  ///< its pose
    std::vector<NeighbourView> neighbours;               ///< nearest first
    std::vector<ClassVote> votes;                        ///< every voted class, winner first
};

/// Votes over `neighbours` (nearest first, as KnnIndex::search returns them) whose view ids
/// index `labels`. Throws std::invalid_argument for no neighbours or a view id out of range.
Classification classify_neighbours(std::span<const KnnNeighbour> neighbours,
                                   std::span<const ViewLabel> labels);

class Classifier {
  public:
    /// Throws std::invalid_argument for an empty index, labels.size() != index.views(), k = 0,
    /// an empty class name, or two class ids for one class name.
    Classifier(KnnIndex index, std::vector<ViewLabel> labels,
               const ClassifierOptions& options = {});

    /// Classifies one descriptor (of the index's dimension, finite).
    Classification classify(std::span<const float> descriptor) const;

    /// Classifies descriptors.size() / dimension descriptors (row-major) on `threads` threads
    /// (0 = all cores); the results do not depend on the thread count.
    std::vector<Classification> classify_batch(std::span<const float> descriptors,
                                               int threads = 0) const;

    const KnnIndex& index() const { return index_; }
    const std::vector<ViewLabel>& labels() const { return labels_; }
    const ClassifierOptions& options() const { return options_; }

  private:
    KnnIndex index_;
    std::vector<ViewLabel> labels_;
    ClassifierOptions options_;
};

}  // namespace esf
