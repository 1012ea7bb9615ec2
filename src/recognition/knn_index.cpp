#include "esf/recognition/knn_index.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "esf/core/parallel.hpp"
#include "recognition/knn_kernels.hpp"

namespace esf {
namespace {

constexpr std::size_t kMaxSketchValues = 64;  // default sketch: at most 64 sums per row
constexpr std::size_t kLaneBytes = 8;         // one SAD lane; one scale per lane
constexpr std::size_t kSketchAlign = 16;      // sketch rows padded to whole 16-byte steps
constexpr double kMaxLaneWeight = 65535.0;    // integer lane weights: 16 bits
constexpr std::size_t kSampleRows = 4096;     // rows sampled to cut the first candidates,
constexpr std::size_t kSampleShare = 8;       // but at most one row in 8
constexpr std::size_t kCutMargin = 4;         // the cut: the (4 * seeds)-th smallest sampled bound
constexpr std::size_t kStoredShare = 4;       // a cut keeping a quarter of the rows: bounds stored
constexpr std::size_t kStoredBytes = std::size_t{8} << 20;  // stored bounds of one turn of queries
constexpr std::size_t kMaxSketchBytes = std::size_t{1} << 27;  // 2^27 * 255 * 65535 < 2^52
constexpr std::size_t kBuildBlock = 1024;                      // rows per build work item
constexpr double kBoundShrink = 1.0 - 1e-9;          // relative slack taken off the sketch distance
constexpr std::size_t kBoundBlockBytes = 24 * 1024;  // sketch rows per block of a pass
constexpr std::size_t kCacheLine = 64;               // bytes fetched by one prefetch
constexpr std::size_t kBoundGroup = 16;    // queries of search_batch() per pass over the sketches
constexpr double kErrorGrow = 1.0 + 1e-9;  // relative slack added to quantisation errors
constexpr double kMagnitudeSlack = 1e-12;  // absolute slack per unit of magnitude
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string describe_value(float v) {
    if (std::isnan(v)) return "NaN";
    return v > 0 ? "+inf" : "-inf";
}

/// The k best views seen so far, sorted by (distance, view); with groups a view appears once,
/// with the smallest distance of its rows (the lowest row at that distance).
class TopViews {
  public:
    TopViews(std::size_t k, bool grouped) : k_(k), grouped_(grouped) { list_.reserve(k + 1); }

    /// Rows whose lower bound exceeds this cannot enter.
    double threshold() const { return threshold_; }

    /// A row of `view`, whose family (or the view itself) is `key`: one entry per key.
    void offer(std::uint32_t key, std::uint32_t view, std::uint32_t row, double distance) {
        if (grouped_) {
            const auto same = std::find(keys_.begin(), keys_.end(), key);
            const auto same_at = same - keys_.begin();
            if (same != keys_.end()) {
                const KnnNeighbour& held = list_[static_cast<std::size_t>(same_at)];
                // Rows may come in any order: keep the smallest distance, then the lowest view
                // (the order of the results), then the lowest row.
                if (distance > held.distance ||
                    (distance == held.distance &&
                     (view > held.view || (view == held.view && row > held.row))))
                    return;
                list_.erase(list_.begin() + same_at);
                keys_.erase(same);
            }
        }
        const KnnNeighbour candidate{view, row, distance};
        if (list_.size() == k_) {
            if (!before(candidate, list_.back())) return;
            list_.pop_back();
            if (grouped_) keys_.pop_back();
        }
        const auto at = std::upper_bound(list_.begin(), list_.end(), candidate, before);
        if (grouped_) keys_.insert(keys_.begin() + (at - list_.begin()), key);
        list_.insert(at, candidate);
        if (list_.size() == k_) threshold_ = list_.back().distance;
    }

    std::vector<KnnNeighbour> take() { return std::move(list_); }

  private:
    static bool before(const KnnNeighbour& a, const KnnNeighbour& b) {
        return a.distance < b.distance || (a.distance == b.distance && a.view < b.view);
    }

    std::size_t k_;
    bool grouped_;
    double threshold_ = kInf;
    std::vector<KnnNeighbour> list_;
    std::vector<std::uint32_t> keys_;  ///< family (or view) of each entry of list_
};

/// Sketch of one row: values[j] = sum of w_i x_i over the `group` dimensions of sum j (zero in
/// the padding); returns the magnitude sum_i w_i |x_i|.
double sketch_values(const float* x, const float* w, std::size_t dimension, std::size_t group,
                     std::span<double> values) {
    std::fill(values.begin(), values.end(), 0.0);
    double magnitude = 0.0;
    for (std::size_t begin = 0, j = 0; begin < dimension; begin += group, ++j) {
        const std::size_t end = std::min(dimension, begin + group);
        double sum = 0.0;
        for (std::size_t i = begin; i < end; ++i) {
            const double v = static_cast<double>(w[i]) * static_cast<double>(x[i]);
            sum += v;
            magnitude += std::fabs(v);
        }
        values[j] = sum;
    }
    return magnitude;
}

}  // namespace

std::vector<float> expand_block_weights(std::span<const float> block_weights,
                                        std::size_t bins_per_block) {
    if (bins_per_block == 0)
        throw std::invalid_argument("expand_block_weights: bins_per_block must be > 0");
    std::vector<float> weights;
    weights.reserve(block_weights.size() * bins_per_block);
    for (const float w : block_weights) weights.insert(weights.end(), bins_per_block, w);
    return weights;
}

KnnIndex::KnnIndex(std::span<const float> rows, std::size_t dimension,
                   const KnnIndexOptions& options) {
    build(rows, dimension, {}, false, options);
}

KnnIndex::KnnIndex(std::span<const float> rows, std::size_t dimension,
                   std::span<const std::uint32_t> row_views, const KnnIndexOptions& options) {
    build(rows, dimension, row_views, true, options);
}

void KnnIndex::build(std::span<const float> rows, std::size_t dimension,
                     std::span<const std::uint32_t> row_views, bool grouped,
                     const KnnIndexOptions& options) {
    if (dimension == 0) throw std::invalid_argument("knn index: dimension must be > 0");
    if (rows.size() % dimension != 0)
        throw std::invalid_argument("knn index: " + std::to_string(rows.size()) +
                                    " values are not a whole number of rows of dimension " +
                                    std::to_string(dimension));
    const std::size_t count = rows.size() / dimension;
    if (count > std::numeric_limits<std::uint32_t>::max())
        throw std::invalid_argument("knn index: too many rows (" + std::to_string(count) + ")");
    if (!options.weights.empty()) {
        if (options.weights.size() != dimension)
            throw std::invalid_argument("knn index: " + std::to_string(options.weights.size()) +
                                        " weights for dimension " + std::to_string(dimension));
        for (std::size_t i = 0; i < dimension; ++i) {
            const float w = options.weights[i];
            if (!std::isfinite(w) || w < 0.0f) {
                std::ostringstream msg;
                msg << "knn index: weight " << i << " is " << w << " (must be finite and >= 0)";
                throw std::invalid_argument(msg.str());
            }
        }
    }
    if (!kernels_supported(options.kernels))
        throw std::invalid_argument(std::string("knn index: kernels ") +
                                    to_string(options.kernels) + " are not supported by this CPU");
    if (options.sketch_group < 0)
        throw std::invalid_argument("knn index: sketch_group must be >= 0, got " +
                                    std::to_string(options.sketch_group));
    const int threads = resolve_threads(options.threads);

    std::size_t views = count;
    if (grouped) {
        if (row_views.size() != count)
            throw std::invalid_argument("knn index: " + std::to_string(row_views.size()) +
                                        " view ids for " + std::to_string(count) + " rows");
        std::vector<std::size_t> per_view;
        for (const std::uint32_t v : row_views) {
            if (v >= per_view.size()) per_view.resize(std::size_t{v} + 1, 0);
            ++per_view[v];
        }
        const auto empty_view = std::find(per_view.begin(), per_view.end(), 0);
        if (empty_view != per_view.end())
            throw std::invalid_argument(
                "knn index: view " + std::to_string(empty_view - per_view.begin()) +
                " has no rows (views must be numbered 0 .. V-1 without gaps)");
        views = per_view.size();
    }

    // First non-finite value, found in parallel, reported deterministically.
    const std::size_t blocks = (count + kBuildBlock - 1) / kBuildBlock;
    std::vector<std::size_t> first_bad(blocks, rows.size());
    parallel_for(blocks, threads, [&](std::size_t b) {
        const std::size_t end = std::min(rows.size(), (b + 1) * kBuildBlock * dimension);
        for (std::size_t i = b * kBuildBlock * dimension; i < end; ++i) {
            if (!std::isfinite(rows[i])) {
                first_bad[b] = i;
                return;
            }
        }
    });
    if (const auto bad = std::min_element(first_bad.begin(), first_bad.end());
        bad != first_bad.end() && *bad < rows.size())
        throw std::invalid_argument("knn index: row " + std::to_string(*bad / dimension) +
                                    " value " + std::to_string(*bad % dimension) + " is " +
                                    describe_value(rows[*bad]));

    std::size_t families = 0;
    if (!options.view_families.empty()) {
        if (options.view_families.size() != views)
            throw std::invalid_argument(
                "knn index: " + std::to_string(options.view_families.size()) +
                " view families for " + std::to_string(views) + " views");
        std::vector<bool> used;
        for (const std::uint32_t f : options.view_families) {
            if (f >= used.size()) {
                if (f >= views)
                    throw std::invalid_argument("knn index: family " + std::to_string(f) +
                                                " out of range (" + std::to_string(views) +
                                                " views)");
                used.resize(std::size_t{f} + 1, false);
            }
            used[f] = true;
        }
        const auto gap = std::find(used.begin(), used.end(), false);
        if (gap != used.end())
            throw std::invalid_argument(
                "knn index: family " + std::to_string(gap - used.begin()) +
                " has no views (families must be numbered 0 .. F-1 without gaps)");
        families = used.size();
    }

    dimension_ = dimension;
    rows_ = count;
    views_ = views;
    families_ = families;
    view_families_ = options.view_families;
    kernels_ = options.kernels == Kernels::kBest ? best_kernels() : options.kernels;
    data_.assign(rows.begin(), rows.end());
    if (grouped) row_views_.assign(row_views.begin(), row_views.end());
    weights_ = options.weights.empty() ? std::vector<float>(dimension, 1.0f) : options.weights;
    group_ = options.sketch_group > 0 ? static_cast<std::size_t>(options.sketch_group)
                                      : (dimension + kMaxSketchValues - 1) / kMaxSketchValues;
    group_ = std::min(group_, dimension);
    sketch_values_ = (dimension + group_ - 1) / group_;
    stride_ = (sketch_values_ + kSketchAlign - 1) / kSketchAlign * kSketchAlign;
    if (stride_ > kMaxSketchBytes)  // the integer sums of the bound must stay below 2^52
        throw std::invalid_argument("knn index: a sketch of " + std::to_string(stride_) +
                                    " bytes per row is too large; raise sketch_group");
    const std::size_t lanes = stride_ / kLaneBytes;

    // Pass 1: range of every lane over all rows (min/max do not depend on the order).
    const int slots = threads;
    std::vector<double> lo(static_cast<std::size_t>(slots) * lanes, kInf);
    std::vector<double> hi(static_cast<std::size_t>(slots) * lanes, -kInf);
    parallel_for_slots(blocks, threads, [&](std::size_t b, int slot) {
        std::vector<double> values(stride_);
        double* slot_lo = lo.data() + static_cast<std::size_t>(slot) * lanes;
        double* slot_hi = hi.data() + static_cast<std::size_t>(slot) * lanes;
        for (std::size_t r = b * kBuildBlock; r < std::min(rows_, (b + 1) * kBuildBlock); ++r) {
            sketch_values(data_.data() + r * dimension_, weights_.data(), dimension_, group_,
                          values);
            for (std::size_t j = 0; j < sketch_values_; ++j) {
                slot_lo[j / kLaneBytes] = std::min(slot_lo[j / kLaneBytes], values[j]);
                slot_hi[j / kLaneBytes] = std::max(slot_hi[j / kLaneBytes], values[j]);
            }
        }
    });
    lane_offset_.assign(lanes, 0.0);
    lane_scale_.assign(lanes, 0.0);
    for (std::size_t l = 0; l < lanes; ++l) {
        double lane_lo = kInf;
        double lane_hi = -kInf;
        for (int s = 0; s < slots; ++s) {
            lane_lo = std::min(lane_lo, lo[static_cast<std::size_t>(s) * lanes + l]);
            lane_hi = std::max(lane_hi, hi[static_cast<std::size_t>(s) * lanes + l]);
        }
        if (!(lane_lo <= lane_hi)) lane_lo = lane_hi = 0.0;  // no rows
        lane_offset_[l] = lane_lo;
        lane_scale_[l] = (lane_hi - lane_lo) / 255.0;
    }
    // Integer lane weights with weight * unit <= scale * (1 - 1e-9): the estimate then never
    // exceeds the distance between the dequantised sketches. Padded to whole 64-byte steps.
    const double max_scale = *std::max_element(lane_scale_.begin(), lane_scale_.end());
    sketch_unit_ = max_scale * kBoundShrink / kMaxLaneWeight;
    lane_weight_.assign((lanes + 7) / 8 * 8, 0);
    for (std::size_t l = 0; l < lanes && sketch_unit_ > 0.0; ++l)
        lane_weight_[l] = static_cast<std::uint32_t>(std::clamp(
            std::floor(lane_scale_[l] * kBoundShrink / sketch_unit_), 0.0, kMaxLaneWeight));

    // Pass 2: 8-bit codes and the quantisation error of every row.
    sketch_.assign(rows_ * stride_, 0);
    row_error_.assign(rows_, 0.0);
    parallel_for(blocks, threads, [&](std::size_t b) {
        std::vector<double> values(stride_);
        for (std::size_t r = b * kBuildBlock; r < std::min(rows_, (b + 1) * kBuildBlock); ++r) {
            const double magnitude = sketch_values(data_.data() + r * dimension_, weights_.data(),
                                                   dimension_, group_, values);
            row_error_[r] = quantise_sketch(values, magnitude, sketch_.data() + r * stride_);
        }
    });
}

double KnnIndex::quantise_sketch(std::span<const double> values, double magnitude,
                                 std::uint8_t* codes) const {
    // error = sum_j |value_j - (offset + scale * code_j)|, widened to cover rounding: of the
    // sums (relative to the magnitude sum_i w_i |x_i|) and of the dequantised values. The
    // padding is 0 in every row and in the query, so it adds nothing to distances or errors.
    std::fill(codes + sketch_values_, codes + stride_, std::uint8_t{0});
    double error = 0.0;
    double dequantised_magnitude = 0.0;
    for (std::size_t j = 0; j < sketch_values_; ++j) {
        const std::size_t l = j / kLaneBytes;
        const double scale = lane_scale_[l];
        double code = 0.0;
        if (scale > 0.0)
            code = std::clamp(std::floor((values[j] - lane_offset_[l]) / scale + 0.5), 0.0, 255.0);
        codes[j] = static_cast<std::uint8_t>(code);
        const double dequantised = lane_offset_[l] + scale * code;
        error += std::fabs(values[j] - dequantised);
        dequantised_magnitude += std::fabs(lane_offset_[l]) + scale * code;
    }
    return error * kErrorGrow + kMagnitudeSlack * (magnitude + dequantised_magnitude);
}

void KnnIndex::check_query(std::span<const float> query, const std::string& what) const {
    if (empty()) throw std::invalid_argument("knn search: the index is empty");
    if (query.size() != dimension_)
        throw std::invalid_argument("knn search: " + what + " has " + std::to_string(query.size()) +
                                    " values, the index has dimension " +
                                    std::to_string(dimension_));
    for (std::size_t i = 0; i < query.size(); ++i)
        if (!std::isfinite(query[i]))
            throw std::invalid_argument("knn search: " + what + " value " + std::to_string(i) +
                                        " is " + describe_value(query[i]));
}

KnnResult KnnIndex::search(std::span<const float> query, std::size_t k) const {
    check_query(query, "query");
    if (k == 0) throw std::invalid_argument("knn search: k must be >= 1");
    return search_checked(query, k);
}

void KnnIndex::sketch_queries(std::span<const float> queries, std::uint8_t* codes,
                              double* errors) const {
    std::vector<double> values(stride_);
    for (std::size_t q = 0; q < queries.size() / dimension_; ++q) {
        const double magnitude = sketch_values(queries.data() + q * dimension_, weights_.data(),
                                               dimension_, group_, values);
        errors[q] = quantise_sketch(values, magnitude, codes + q * stride_);
    }
}

void KnnIndex::collect_candidates(std::size_t count, const std::uint8_t* codes,
                                  const double* errors, const double* limits,
                                  const Candidate* after,
                                  std::vector<Candidate>* candidates) const {
    const detail::KnnKernels kernels = detail::knn_kernels(kernels_);
    // Rows in blocks that stay in the first-level cache while every query passes over them: the
    // sketches are read from memory once per pass, whatever the number of queries, and only the
    // few rows under a query's limit leave the kernel.
    const std::size_t block = std::max<std::size_t>(8, kBoundBlockBytes / stride_ / 8 * 8);
    std::vector<double> bound(block);
    std::vector<std::uint32_t> row(block);
    for (std::size_t r = 0; r < rows_; r += block) {
        const std::size_t n = std::min(block, rows_ - r);
        for (std::size_t q = 0; q < count; ++q) {
            const std::size_t kept =
                kernels.sketch(sketch_.data() + r * stride_, n, stride_, codes + q * stride_,
                               lane_weight_.data(), sketch_unit_, row_error_.data() + r, errors[q],
                               limits[q], static_cast<std::uint32_t>(r), bound.data(), row.data());
            for (std::size_t i = 0; i < kept; ++i)
                if (const Candidate candidate{bound[i], row[i]}; after[q] < candidate)
                    candidates[q].push_back(candidate);
        }
    }
}

void KnnIndex::all_bounds(std::size_t count, const std::uint8_t* codes, const double* errors,
                          double* bounds) const {
    const detail::KnnKernels kernels = detail::knn_kernels(kernels_);
    const std::size_t block = std::max<std::size_t>(8, kBoundBlockBytes / stride_ / 8 * 8);
    std::vector<std::uint32_t> row(block);
    for (std::size_t r = 0; r < rows_; r += block) {
        const std::size_t n = std::min(block, rows_ - r);
        for (std::size_t q = 0; q < count; ++q)  // no limit: every row's bound, in row order
            kernels.sketch(sketch_.data() + r * stride_, n, stride_, codes + q * stride_,
                           lane_weight_.data(), sketch_unit_, row_error_.data() + r, errors[q],
                           kInf, static_cast<std::uint32_t>(r), bounds + q * rows_ + r, row.data());
    }
}

std::size_t KnnIndex::wanted(std::size_t k) const {
    return std::min(k, has_families() ? families_ : views_);
}

std::size_t KnnIndex::seed_count(std::size_t want) const {
    // With families the seeds are as many rows as `want` families hold on average, so that they
    // usually hold `want` families.
    return has_families() ? std::min(rows_, want * ((rows_ + families_ - 1) / families_)) : want;
}

void KnnIndex::search_group(std::span<const float> queries, std::size_t k,
                            KnnResult* results) const {
    const std::size_t count = queries.size() / dimension_;
    std::vector<std::uint8_t> codes(count * stride_);
    std::vector<double> errors(count);
    sketch_queries(queries, codes.data(), errors.data());

    // Any `seeds` rows bound the seeds-th smallest bound from above, so a small rank of the
    // bounds of a sample of rows (evenly spread, and few: the sample is read besides the pass)
    // cuts the candidates for the first exact distances to a few. The cut is taken kCutMargin
    // times further than the seeds need, so that it usually exceeds the k-th distance too: then
    // one pass finds every candidate.
    const std::size_t seeds = seed_count(wanted(k));
    const std::size_t sample =
        std::min(rows_, std::max(seeds, std::min(kSampleRows, rows_ / kSampleShare)));
    const std::size_t rank = std::min(sample, kCutMargin * seeds);
    std::vector<std::vector<Candidate>> below_cut(count);
    if (kStoredShare * rank >= sample) {
        // The cut would keep a large share of the rows (small indexes with families, whose
        // seeds are many rows): every row's bound is stored instead, one pass, and the cut is
        // the seeds-th smallest of kSampleRows of them; later passes read the stored bounds.
        // Queries share a pass in turns of at most kStoredBytes of bounds (one query's at least).
        const std::size_t stored_sample = std::min(rows_, std::max(kSampleRows, seeds));
        const std::size_t turn =
            std::clamp<std::size_t>(kStoredBytes / (rows_ * sizeof(double)), 1, count);
        std::vector<double> bounds(turn * rows_);
        std::vector<double> sampled(stored_sample);
        for (std::size_t first = 0; first < count; first += turn) {
            const std::size_t n = std::min(turn, count - first);
            all_bounds(n, codes.data() + first * stride_, errors.data() + first, bounds.data());
            for (std::size_t q = first; q < first + n; ++q) {
                const double* bound = bounds.data() + (q - first) * rows_;
                for (std::size_t i = 0; i < stored_sample; ++i)
                    sampled[i] = bound[i * rows_ / stored_sample];
                std::nth_element(sampled.begin(),
                                 sampled.begin() + static_cast<std::ptrdiff_t>(seeds - 1),
                                 sampled.end());
                const double cut = sampled[seeds - 1];
                for (std::size_t r = 0; r < rows_; ++r)
                    if (bound[r] <= cut)
                        below_cut[q].emplace_back(bound[r], static_cast<std::uint32_t>(r));
                results[q] =
                    search_bounded(queries.subspan(q * dimension_, dimension_), k,
                                   codes.data() + q * stride_, errors[q], cut, below_cut[q], bound);
            }
        }
        return;
    }
    std::vector<std::uint8_t> sample_codes;
    std::vector<double> sample_errors;
    const std::uint8_t* sample_sketch = sketch_.data();
    const double* sample_error = row_error_.data();
    if (sample < rows_) {
        sample_codes.resize(sample * stride_);
        sample_errors.resize(sample);
        for (std::size_t i = 0; i < sample; ++i) {
            const std::size_t r = i * rows_ / sample;
            std::copy_n(sketch_.data() + r * stride_, stride_, sample_codes.data() + i * stride_);
            sample_errors[i] = row_error_[r];
        }
        sample_sketch = sample_codes.data();
        sample_error = sample_errors.data();
    }
    const detail::KnnKernels kernels = detail::knn_kernels(kernels_);
    std::vector<double> sampled(sample);
    std::vector<std::uint32_t> sampled_rows(sample);
    std::vector<double> cuts(count);
    for (std::size_t q = 0; q < count; ++q) {
        kernels.sketch(sample_sketch, sample, stride_, codes.data() + q * stride_,
                       lane_weight_.data(), sketch_unit_, sample_error, errors[q], kInf, 0,
                       sampled.data(), sampled_rows.data());
        std::nth_element(sampled.begin(), sampled.begin() + static_cast<std::ptrdiff_t>(rank - 1),
                         sampled.end());
        cuts[q] = sampled[rank - 1];
    }

    const std::vector<Candidate> from_start(count, Candidate{-kInf, 0});
    collect_candidates(count, codes.data(), errors.data(), cuts.data(), from_start.data(),
                       below_cut.data());
    for (std::size_t q = 0; q < count; ++q)
        results[q] =
            search_bounded(queries.subspan(q * dimension_, dimension_), k,
                           codes.data() + q * stride_, errors[q], cuts[q], below_cut[q], nullptr);
}

KnnResult KnnIndex::search_checked(std::span<const float> query, std::size_t k) const {
    KnnResult result;
    search_group(query, k, &result);
    return result;
}

void KnnIndex::prefetch_row(std::size_t row) const {
    // The rows refined lie anywhere in memory: fetching the next one while the current one is
    // refined hides most of the memory latency.
    const char* begin = reinterpret_cast<const char*>(data_.data() + row * dimension_);
    const char* end = reinterpret_cast<const char*>(data_.data() + (row + 1) * dimension_);
    for (const char* line = begin; line < end; line += kCacheLine) __builtin_prefetch(line);
}

KnnResult KnnIndex::search_bounded(std::span<const float> query, std::size_t k,
                                   const std::uint8_t* codes, double error, double cut,
                                   std::vector<Candidate>& below_cut, const double* stored) const {
    const detail::KnnKernels distances = detail::knn_kernels(kernels_);

    // Optimal multi-step search (Seidl & Kriegel): lower bounds of all rows (see the header);
    // exact distances for the rows with the smallest bounds, which sets the k-th distance;
    // then exact distances for the other rows whose bound does not exceed the k-th distance,
    // in increasing bound order, until the next bound exceeds it. The result does not depend
    // on the order; the order only makes the k-th distance fall fast.
    const std::size_t want = wanted(k);
    TopViews top(want, grouped() || has_families());
    KnnResult result;
    const auto refine = [&](std::vector<Candidate>& candidates) {
        std::sort(candidates.begin(), candidates.end());
        for (std::size_t i = 0; i < candidates.size(); ++i) {
            const auto [row_bound, row] = candidates[i];
            if (row_bound > top.threshold()) break;
            if (i + 1 < candidates.size()) prefetch_row(candidates[i + 1].second);
            const std::uint32_t view = view_of(row);
            top.offer(family_of(view), view, row,
                      distances.exact(query.data(), data_.data() + row * dimension_,
                                      weights_.data(), dimension_, top.threshold()));
            ++result.exact_distances;
        }
    };

    // The seeds: the `seeds` smallest (bound, row) pairs, all below the cut; the other rows are
    // the pairs after the last seed.
    const std::size_t seeds = seed_count(want);
    const auto seeds_end = below_cut.begin() + static_cast<std::ptrdiff_t>(seeds);
    std::nth_element(below_cut.begin(), seeds_end - 1, below_cut.end());
    const Candidate last_seed = *(seeds_end - 1);
    const auto rows_below = [&](double limit, std::vector<Candidate>& out) {
        if (!stored) {
            collect_candidates(1, codes, &error, &limit, &last_seed, &out);
            return;
        }
        for (std::size_t r = 0; r < rows_; ++r)
            if (const Candidate c{stored[r], static_cast<std::uint32_t>(r)};
                c.first <= limit && last_seed < c)
                out.push_back(c);
    };
    std::vector<Candidate> candidates(below_cut.begin(), seeds_end);
    refine(candidates);

    // With groups or families the seeds may share views or families and leave the threshold
    // infinite: then the other rows are refined in batches of the smallest bounds, each twice
    // the last, until `want` views or families are held.
    if (top.threshold() == kInf) {
        std::vector<Candidate> rest;
        rows_below(kInf, rest);
        auto begin = rest.begin();
        for (std::size_t batch = 4 * want; top.threshold() == kInf && begin != rest.end();
             batch *= 2) {
            const auto end = rest.end() - begin > static_cast<std::ptrdiff_t>(batch)
                                 ? begin + static_cast<std::ptrdiff_t>(batch)
                                 : rest.end();
            std::nth_element(begin, end - 1, rest.end());
            candidates.assign(begin, end);
            refine(candidates);
            begin = end;
        }
        candidates.clear();
        const double threshold = top.threshold();
        std::copy_if(begin, rest.end(), std::back_inserter(candidates),
                     [&](const Candidate& c) { return c.first <= threshold; });
        refine(candidates);
        result.neighbours = top.take();
        return result;
    }

    // The others whose bound does not exceed the k-th distance: among those below the cut when
    // it is not below the k-th distance, else from another pass over the sketches.
    const double threshold = top.threshold();
    candidates.clear();
    if (threshold <= cut)
        std::copy_if(seeds_end, below_cut.end(), std::back_inserter(candidates),
                     [&](const Candidate& c) { return c.first <= threshold; });
    else
        rows_below(threshold, candidates);
    refine(candidates);
    result.neighbours = top.take();
    return result;
}

std::vector<KnnResult> KnnIndex::search_batch(std::span<const float> queries, std::size_t k,
                                              int threads) const {
    if (empty()) throw std::invalid_argument("knn search: the index is empty");
    if (k == 0) throw std::invalid_argument("knn search: k must be >= 1");
    if (queries.size() % dimension_ != 0)
        throw std::invalid_argument("knn search: " + std::to_string(queries.size()) +
                                    " query values are not a whole number of queries of "
                                    "dimension " +
                                    std::to_string(dimension_));
    const std::size_t count = queries.size() / dimension_;
    for (std::size_t q = 0; q < count; ++q)
        check_query(queries.subspan(q * dimension_, dimension_), "query " + std::to_string(q));
    // Queries in groups of up to kBoundGroup share each pass over the sketches (search_group),
    // as many groups as threads when there are fewer queries than that.
    const std::size_t workers = static_cast<std::size_t>(resolve_threads(threads));
    const std::size_t groups =
        std::min(count, std::max((count + kBoundGroup - 1) / kBoundGroup, workers));
    std::vector<KnnResult> results(count);
    parallel_for(groups, threads, [&](std::size_t g) {
        const std::size_t begin = g * count / groups;
        const std::size_t end = (g + 1) * count / groups;
        search_group(queries.subspan(begin * dimension_, (end - begin) * dimension_), k,
                     results.data() + begin);
    });
    return results;
}

double KnnIndex::distance(std::span<const float> query, std::size_t row) const {
    check_query(query, "query");
    if (row >= rows_)
        throw std::invalid_argument("knn index: row " + std::to_string(row) + " out of range (" +
                                    std::to_string(rows_) + " rows)");
    return detail::knn_kernels(kernels_).exact(query.data(), data_.data() + row * dimension_,
                                               weights_.data(), dimension_, kInf);
}

std::size_t KnnIndex::memory_bytes() const {
    return data_.size() * sizeof(float) + weights_.size() * sizeof(float) +
           (row_views_.size() + view_families_.size()) * sizeof(std::uint32_t) + sketch_.size() +
           row_error_.size() * sizeof(double) +
           (lane_offset_.size() + lane_scale_.size()) * sizeof(double) +
           lane_weight_.size() * sizeof(std::uint32_t);
}

}  // namespace esf
