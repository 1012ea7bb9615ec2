#pragma once
// Classification from the k nearest database views or models (Wohlkinger & Vincze 2011,
// Sec. IV: the class of the nearest training views by L1 distance).
//
// Rule kNearest (the default): the class of the nearest neighbour, as the paper's 1-NN; the k
// neighbours still vote, and the confidence is the share of them that has that class. Rule
// kMajority: each neighbour casts one vote for its class and the most votes win; equal vote counts
// go to the smaller sum of the voters' distances, then to the class of the nearer neighbour; the
// confidence is the winner's share of the votes. With one view per model (the recognizer's
// default) a majority favours the classes with many models (boxes and cans, in the shared
// meshes): on the real views it names 75.9 % right against 77.6 % for the nearest, and on the
// synthetic held-out views 56 % against 63 % (BENCHMARKS.md). Either way k = 1 gives the class of
// the nearest view, and the best model, view and pose are those of the nearest view of the
// winning class.
//
// The classifier holds a KnnIndex and one ViewLabel per index view, all in memory; it does not
// care where they came from (a database, a test, another descriptor). Thread safety: classify()
// and classify_batch() are const and may run concurrently.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "esf/core/enum_names.hpp"
#include "esf/recognition/knn_index.hpp"
#include "esf/recognition/pose_verification.hpp"

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

/// How the k neighbours name the class (see the top of the file).
enum class VoteRule {
    kNearest,   ///< the nearest neighbour's class; the others give the confidence
    kMajority,  ///< the most frequent class among the k neighbours
};

/// "nearest", "majority" (to_string, parse_enum<VoteRule>).
template <>
struct EnumNames<VoteRule> {
    static constexpr const char* what = "vote rule";
    static constexpr std::array<EnumName<VoteRule>, 2> table{
        {{VoteRule::kNearest, "nearest"}, {VoteRule::kMajority, "majority"}}};
};

struct ClassifierOptions {
    std::size_t k = 10;  ///< neighbours that vote (fewer when the index has fewer)
    VoteRule vote = VoteRule::kNearest;
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
    double confidence = 0.0;  ///< share of the neighbours of the winning class, in (0, 1]
    std::string best_model;   ///< model of the nearest view of the winning class
    int best_model_id = -1;
    int best_view = 0;
    std::uint32_t best_index = 0;  ///< its view id in the index
    double best_distance = 0.0;
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();  ///< its pose
    std::vector<NeighbourView> neighbours;               ///< nearest first
    std::vector<ClassVote> votes;                        ///< every voted class, winner first
    /// Set by verification (RecognizerOptions::verification_meshes): the chosen model's fit under
    /// `pose`, which is then the model aligned to the points (mesh file -> camera, scale
    /// included), not the training view's; the neighbours are reordered, best fit first.
    std::optional<FitScore> fit;
    bool verified = false;  ///< a candidate met the verification thresholds
    /// The query's cylinder-box contrast (primitive_contrast of its descriptor's block); NaN
    /// where the descriptor has no such block or the classification came from neighbours alone.
    double shape_contrast = std::numeric_limits<double>::quiet_NaN();
};

/// Makes `n` the classification's choice: class, model, view, index, distance and pose (the
/// confidence and votes are left as they are).
void adopt_neighbour(Classification& c, const NeighbourView& n);

/// Classifies by `rule` from `neighbours` (nearest first, as KnnIndex::search returns them)
/// whose view ids index `labels`. Throws std::invalid_argument for no neighbours or a view id
/// out of range.
Classification classify_neighbours(std::span<const KnnNeighbour> neighbours,
                                   std::span<const ViewLabel> labels,
                                   VoteRule rule = VoteRule::kNearest);

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
