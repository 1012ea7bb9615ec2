#include "esf/evaluation/weight_learning.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include "esf/core/parallel.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/recognition/knn_index.hpp"
#include "evaluation/lomo_search.hpp"

namespace esf {

namespace {

/// The candidates of every query under some weights: their per-block L1 distances and whether
/// they have the query's class. Query q's candidates are entries [q * c, q * c + count[q]).
struct CandidateSet {
    std::vector<double> query_weight;  // queries, summing to 1
    std::size_t blocks = 0;
    std::size_t per_query = 0;
    std::vector<float> block_distance;  // queries x per_query x blocks
    std::vector<std::uint8_t> same;     // queries x per_query
    std::vector<std::uint32_t> count;   // queries
};

struct Exact {
    double objective = 0.0;
    double top1 = 0.0;
    CandidateSet candidates;
};

double margin_of(double a, double b) { return a + b > 0.0 ? (b - a) / (a + b) : 0.0; }

std::vector<float> normalised(std::vector<double> w) {
    double sum = 0.0;
    for (const double v : w) sum += v;
    std::vector<float> out(w.size());
    for (std::size_t b = 0; b < w.size(); ++b)
        out[b] = static_cast<float>(w[b] * static_cast<double>(w.size()) / sum);
    return out;
}

/// Exact objective of block weights `w` over `queries`, and the candidates it searched.
Exact exact_objective(const DescriptorMatrix& matrix, const detail::LomoSetup& setup,
                      const std::vector<std::size_t>& queries,
                      const std::vector<double>& query_weight, const std::vector<float>& w,
                      const std::vector<std::size_t>& block_sizes,
                      const WeightLearningOptions& options, int threads) {
    const std::size_t blocks = block_sizes.size(), c = options.candidates;
    std::vector<std::size_t> block_begin(blocks + 1, 0);
    std::vector<float> dimension_weights;
    for (std::size_t b = 0; b < blocks; ++b) {
        block_begin[b + 1] = block_begin[b] + block_sizes[b];
        dimension_weights.insert(dimension_weights.end(), block_sizes[b], w[b]);
    }
    const KnnIndex index =
        detail::lomo_index(matrix, setup, dimension_weights, threads, /*per_model=*/false);
    Exact out;
    CandidateSet& set = out.candidates;
    set.query_weight = query_weight;
    set.blocks = blocks;
    set.per_query = c;
    set.block_distance.assign(queries.size() * c * blocks, 0.0f);
    set.same.assign(queries.size() * c, 0);
    set.count.assign(queries.size(), 0);
    std::vector<double> hit(queries.size(), 0.0), margin(queries.size(), 0.0);
    parallel_for(queries.size(), threads, [&](std::size_t q) {
        const std::size_t view = queries[q];
        const std::vector<KnnNeighbour> nearest = detail::lomo_search(index, setup, view, c);
        if (nearest.empty()) return;
        const std::uint32_t cls = setup.view_category[view];
        const std::span<const float> a = matrix.row(setup.view_first_row[view]);
        double same_d = -1.0, other_d = -1.0;
        for (std::size_t j = 0; j < nearest.size(); ++j) {
            const KnnNeighbour& n = nearest[j];
            const bool same = setup.view_category[n.view] == cls;
            set.same[q * c + j] = same ? 1 : 0;
            if (same && same_d < 0.0) same_d = n.distance;
            if (!same && other_d < 0.0) other_d = n.distance;
            const std::span<const float> b = matrix.row(setup.view_first_row[n.view]);
            float* out_d = &set.block_distance[(q * c + j) * blocks];
            for (std::size_t k = 0; k < blocks; ++k) {
                double s = 0.0;
                for (std::size_t i = block_begin[k]; i < block_begin[k + 1]; ++i)
                    s += std::abs(static_cast<double>(a[i]) - static_cast<double>(b[i]));
                out_d[k] = static_cast<float>(s);
            }
        }
        set.count[q] = static_cast<std::uint32_t>(nearest.size());
        const double farthest = nearest.back().distance;
        hit[q] = setup.view_category[nearest.front().view] == cls ? 1.0 : 0.0;
        margin[q] = margin_of(same_d < 0.0 ? farthest : same_d, other_d < 0.0 ? farthest : other_d);
    });
    double hits = 0.0, objective = 0.0;
    for (std::size_t q = 0; q < queries.size(); ++q) {
        hits += hit[q];
        objective += query_weight[q] * (hit[q] + options.smooth * margin[q]);
    }
    out.top1 = hits / static_cast<double>(queries.size());
    out.objective = objective;
    return out;
}

/// The objective restricted to the candidates, for block weights exp(x).
double candidate_objective(const CandidateSet& set, const std::vector<double>& x, double smooth) {
    const std::size_t blocks = set.blocks, c = set.per_query, queries = set.count.size();
    std::vector<double> w(blocks);
    for (std::size_t b = 0; b < blocks; ++b) w[b] = std::exp(x[b]);
    double objective = 0.0;
    for (std::size_t q = 0; q < queries; ++q) {
        const std::size_t count = set.count[q];
        if (count == 0) continue;
        double nearest = std::numeric_limits<double>::infinity(), farthest = 0.0;
        double same_d = nearest, other_d = nearest;
        bool nearest_same = false;
        for (std::size_t j = 0; j < count; ++j) {
            const float* d = &set.block_distance[(q * c + j) * blocks];
            double s = 0.0;
            for (std::size_t b = 0; b < blocks; ++b) s += w[b] * static_cast<double>(d[b]);
            const bool same = set.same[q * c + j] != 0;
            if (s < nearest) {
                nearest = s;
                nearest_same = same;
            }
            farthest = std::max(farthest, s);
            if (same)
                same_d = std::min(same_d, s);
            else
                other_d = std::min(other_d, s);
        }
        const double margin = margin_of(std::isinf(same_d) ? farthest : same_d,
                                        std::isinf(other_d) ? farthest : other_d);
        objective += set.query_weight[q] * ((nearest_same ? 1.0 : 0.0) + smooth * margin);
    }
    return objective;
}

/// Coordinate pattern search on the candidates' objective from log-weights x0, each coordinate
/// within +-radius of x0 and within the weight bounds. Returns the best log-weights found.
std::vector<double> pattern_search(const CandidateSet& set, const std::vector<double>& x0,
                                   double radius, const WeightLearningOptions& options) {
    constexpr int kMaxEvaluations = 3000;
    std::vector<double> x = x0;
    double f = candidate_objective(set, x, options.smooth);
    const double low = std::log(options.min_weight), high = std::log(options.max_weight);
    double step = std::min(options.initial_step, radius);
    int evaluations = 0;
    while (step >= options.min_step && evaluations < kMaxEvaluations) {
        bool improved = false;
        for (std::size_t b = 0; b < x.size() && evaluations < kMaxEvaluations; ++b) {
            for (const double direction : {1.0, -1.0}) {
                std::vector<double> y = x;
                y[b] = std::clamp(y[b] + direction * step, std::max(low, x0[b] - radius),
                                  std::min(high, x0[b] + radius));
                if (y[b] == x[b]) continue;
                const double fy = candidate_objective(set, y, options.smooth);
                ++evaluations;
                if (fy > f + 1e-12) {
                    x = std::move(y);
                    f = fy;
                    improved = true;
                    break;
                }
            }
        }
        if (!improved) step *= 0.5;
    }
    return x;
}

void check_options(const DescriptorMatrix& matrix, const WeightLearningOptions& o,
                   const std::vector<std::size_t>& blocks) {
    auto fail = [](const std::string& what) {
        throw std::invalid_argument("learn_weights: " + what);
    };
    if (blocks.empty()) fail("no blocks");
    std::size_t total = 0;
    for (const std::size_t size : blocks) {
        if (size == 0) fail("a block of size 0");
        total += size;
    }
    if (matrix.kind.dimension <= 0 || total != static_cast<std::size_t>(matrix.kind.dimension))
        fail("blocks of " + std::to_string(total) + " bins in all for dimension " +
             std::to_string(matrix.kind.dimension));
    if (o.candidates < 2) fail("candidates must be >= 2, got " + std::to_string(o.candidates));
    if (!(o.smooth >= 0.0) || !std::isfinite(o.smooth))
        fail("smooth must be finite and >= 0, got " + std::to_string(o.smooth));
    if (o.max_iterations < 0) fail("max_iterations must be >= 0");
    if (!(o.initial_step > 0.0) || !std::isfinite(o.initial_step))
        fail("initial_step must be > 0, got " + std::to_string(o.initial_step));
    if (!(o.min_step > 0.0) || !std::isfinite(o.min_step))
        fail("min_step must be > 0, got " + std::to_string(o.min_step));
    if (!(o.trust_region > 0.0) || !std::isfinite(o.trust_region))
        fail("trust_region must be > 0, got " + std::to_string(o.trust_region));
    if (!(o.min_weight > 0.0) || !(o.max_weight > o.min_weight) || !std::isfinite(o.max_weight))
        fail("need 0 < min_weight < max_weight, got " + std::to_string(o.min_weight) + " and " +
             std::to_string(o.max_weight));
    if (!o.initial.empty()) {
        if (o.initial.size() != blocks.size())
            fail(std::to_string(o.initial.size()) + " initial weights for " +
                 std::to_string(blocks.size()) + " blocks");
        for (const float v : o.initial)
            if (!(v > 0.0f) || !std::isfinite(v))
                fail("initial weights must be finite and > 0, got " + std::to_string(v));
    }
}

}  // namespace

WeightLearningResult learn_weights(const DescriptorMatrix& trained,
                                   const WeightLearningOptions& options) {
    // Views with occluded copies learn from their own signatures.
    const DescriptorMatrix matrix =
        detail::has_occluded_copies(trained) ? detail::own_view_signatures(trained) : trained;
    const std::vector<std::size_t> blocks =
        options.blocks.empty() ? descriptor_blocks(descriptor_info(matrix.kind.name))
                               : options.blocks;
    check_options(matrix, options, blocks);
    const int threads = resolve_threads(options.threads);
    const detail::LomoSetup setup = detail::lomo_setup(matrix, options.groups, "learn_weights");
    if (setup.multi_signature)
        throw std::invalid_argument("learn_weights: " + matrix.kind.name +
                                    " views have several signatures; block weights need one");
    const std::vector<std::size_t> queries =
        detail::lomo_queries(setup.views(), options.max_queries);
    // Each query's share of the objective: 1 / queries, or 1 / (classes x queries of its class).
    std::vector<double> query_weight(queries.size(), 1.0 / static_cast<double>(queries.size()));
    if (options.class_balanced) {
        std::vector<std::size_t> per_class(matrix.categories.size(), 0);
        for (const std::size_t v : queries) ++per_class[setup.view_category[v]];
        std::size_t classes = 0;
        for (const std::size_t n : per_class) classes += n > 0;
        for (std::size_t q = 0; q < queries.size(); ++q)
            query_weight[q] =
                1.0 / static_cast<double>(classes * per_class[setup.view_category[queries[q]]]);
    }

    std::vector<double> start(blocks.size(), 1.0);
    for (std::size_t b = 0; b < options.initial.size(); ++b) start[b] = options.initial[b];
    std::vector<float> w = normalised(start);

    Exact current =
        exact_objective(matrix, setup, queries, query_weight, w, blocks, options, threads);
    WeightLearningResult result;
    result.queries = queries.size();
    result.objective_before = current.objective;
    result.top1_before = current.top1;
    double radius = options.trust_region;
    for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
        std::vector<double> x(blocks.size());
        for (std::size_t b = 0; b < blocks.size(); ++b) x[b] = std::log(static_cast<double>(w[b]));
        const std::vector<double> y = pattern_search(current.candidates, x, radius, options);
        if (y == x) break;  // no better weights among the candidates
        std::vector<double> proposal(blocks.size());
        for (std::size_t b = 0; b < blocks.size(); ++b) proposal[b] = std::exp(y[b]);
        const std::vector<float> v = normalised(proposal);
        Exact next =
            exact_objective(matrix, setup, queries, query_weight, v, blocks, options, threads);
        ++result.iterations;
        if (next.objective > current.objective) {
            w = v;
            current = std::move(next);
            ++result.accepted;
        } else {
            radius *= 0.5;
        }
        result.history.push_back(current.objective);
        if (options.progress) options.progress(result.iterations, current.objective);
        if (radius < options.min_step) break;
    }
    result.weights = w;
    result.objective_after = current.objective;
    result.top1_after = current.top1;
    return result;
}

}  // namespace esf
