#pragma once
// Learning the weights of a descriptor's blocks (ESF: its ten sub-histograms, Wohlkinger &
// Vincze 2011, Sec. III) on synthetic views only, so that no real data is needed:
//
//     distance(q, v) = sum_b w_b * L1_b(q, v)          (L1_b: the L1 distance over block b)
//
// Objective (leave-one-model-out, or leave-one-group-out with groups): over a deterministic
// subset of the database's views as queries, each searched among the views of the other groups,
//     objective(w) = mean(1-NN hit + smooth * (b - a) / (a + b))
// with a the distance of the nearest view of the true class and b that of the nearest view of
// another class among the `candidates` nearest (where one of them is absent, the largest of the
// candidates' distances stands in). The second term breaks ties between weights of equal
// accuracy in favour of wider margins; it lies in [-smooth, smooth]. The mean is over the
// classes of the means over their queries (class_balanced, the paper's per-class accuracy, so
// that a category of 60 models does not outweigh one of 2), or over all queries.
//
// Search: a pattern search over the log-weights. Each iteration takes the `candidates` nearest
// views of every query under the current weights (an exact search), then improves the objective
// restricted to those candidates (whose per-block distances are kept: evaluating it costs
// queries x candidates x blocks multiply-adds) by coordinate steps of +-step on one log-weight
// at a time, halving the step when no coordinate improves, within a trust region around the
// current weights. The proposal is accepted only when the exact objective improves; otherwise
// the trust region halves. So the exact objective never decreases from one iteration to the
// next, and the weights, the objectives and the iterations are the same for any thread count.
// Weights are normalised to mean 1 (the objective does not depend on their scale).
//
// Cost: about one leave-one-model-out search of `max_queries` queries per iteration (k =
// candidates + the views of the query's group): seconds for a database of 15,000 ESF views.

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "esf/training/database.hpp"

namespace esf {

/// Called after each iteration: (iteration, exact objective of the current weights). Called on
/// the calling thread; it may throw to stop learning (the exception propagates).
using WeightLearningProgress = std::function<void(int, double)>;

struct WeightLearningOptions {
    /// Sizes of the blocks weighted apart, summing to the descriptor's dimension; empty: the
    /// blocks the descriptor registry lists for matrix.kind (DescriptorInfo::blocks; ESF: ten
    /// of kEsfBins).
    std::vector<std::size_t> blocks;
    /// Group of each model (matrix.models order), as SyntheticOptions::groups; empty:
    /// leave-one-model-out.
    std::vector<std::string> groups;
    /// Queries: at most this many views, evenly spaced over the matrix (0 = every view).
    std::size_t max_queries = 3000;
    std::size_t candidates = 30;  ///< nearest views kept per query (>= 2)
    double smooth = 0.05;         ///< weight of the margin term (>= 0)
    /// Mean over classes of the per-class means (true) or over all queries (false).
    bool class_balanced = true;
    int max_iterations = 12;    ///< exact searches after the first (>= 0)
    double initial_step = 0.5;  ///< first step on a log-weight (> 0)
    double min_step = 0.03;     ///< the search stops below this step (> 0)
    double trust_region = 1.0;  ///< largest change of a log-weight per iteration (> 0)
    /// Bounds of the search on each weight (before the weights are rescaled to mean 1).
    double min_weight = 0.01;
    double max_weight = 20.0;
    /// Starting block weights (one per block, finite, > 0); empty: all 1.
    std::vector<float> initial;
    int threads = 0;  ///< 0 = all cores
    WeightLearningProgress progress;
};

struct WeightLearningResult {
    std::vector<float> weights;     ///< one per block, mean 1
    double objective_before = 0.0;  ///< exact objective of the initial weights
    double objective_after = 0.0;   ///< exact objective of `weights` (>= objective_before)
    double top1_before = 0.0;       ///< 1-NN accuracy per query, initial weights
    double top1_after = 0.0;        ///< and with `weights`
    int iterations = 0;             ///< exact searches after the first
    int accepted = 0;               ///< iterations whose proposal was accepted
    std::vector<double> history;    ///< exact objective after each iteration (non-decreasing)
    std::size_t queries = 0;        ///< query views used
};

/// Learns block weights on the views of `matrix` (one signature per view). Throws
/// std::invalid_argument for a dimension that is not a multiple of options.blocks, a matrix with
/// several signatures per view, without views or with fewer than two groups, and options out
/// of range (naming the option).
WeightLearningResult learn_weights(const DescriptorMatrix& matrix,
                                   const WeightLearningOptions& options = {});

}  // namespace esf
