#include "esf/evaluation/evaluation.hpp"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/csv.hpp"
#include "core/elapsed_time.hpp"
#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "esf/io/cloud_io.hpp"
#include "evaluation/lomo_search.hpp"

namespace esf {

namespace {

namespace fs = std::filesystem;
using detail::CsvRecord;
using detail::lower;
using detail::parse_csv;
using detail::trim;

using detail::seconds_since;

// ---- metrics --------------------------------------------------------------------------------

struct ClassTally {
    std::size_t samples = 0, failed = 0;
    std::vector<std::size_t> ranks;  // ranks[r] = queries of rank r (0 = beyond k)
    std::map<std::string, std::size_t> wrong;
};

std::vector<double> curve_of(const std::vector<std::size_t>& ranks, std::size_t samples) {
    std::vector<double> curve(ranks.size() - 1, 0.0);
    std::size_t hits = 0;
    for (std::size_t r = 1; r < ranks.size(); ++r) {
        hits += ranks[r];
        curve[r - 1] = samples ? static_cast<double>(hits) / static_cast<double>(samples) : 0.0;
    }
    return curve;
}

double ratio(std::size_t a, std::size_t b) {
    return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0;
}

/// The neighbour lists of a query's signatures merged into its k nearest views.
std::vector<OutcomeNeighbour> outcome_neighbours(std::span<const KnnNeighbour> neighbours,
                                                 std::span<const ViewLabel> labels) {
    std::vector<OutcomeNeighbour> out;
    out.reserve(neighbours.size());
    for (const KnnNeighbour& n : neighbours) out.push_back({labels[n.view].class_name, n.distance});
    return out;
}

/// Serialises progress calls.
class ProgressCounter {
  public:
    ProgressCounter(const EvaluationProgress& progress, std::size_t total)
        : progress_(progress), total_(total) {}
    void tick() {
        const std::size_t done = ++done_;
        if (!progress_) return;
        const std::lock_guard<std::mutex> lock(mutex_);
        progress_(done, total_);
    }

  private:
    const EvaluationProgress& progress_;
    std::size_t total_;
    std::atomic<std::size_t> done_{0};
    std::mutex mutex_;
};

}  // namespace

// ---- test sets ------------------------------------------------------------------------------

TestSet read_test_set(std::istream& in, const std::string& path) {
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw IoError(file_message(path, 0, "read failed"));
    const std::vector<CsvRecord> records = parse_csv(text, path);
    if (records.empty())
        throw IoError(file_message(path, 0, "empty file (expected a header with file and class)"));
    const CsvRecord& header = records.front();
    std::size_t file_column = header.fields.size(), class_column = header.fields.size();
    for (std::size_t c = 0; c < header.fields.size(); ++c) {
        const std::string name = lower(trim(header.fields[c]));
        if (name == "file" && file_column == header.fields.size()) file_column = c;
        if (name == "class" && class_column == header.fields.size()) class_column = c;
    }
    for (const auto& [column, name] :
         {std::pair{file_column, "file"}, std::pair{class_column, "class"}})
        if (column == header.fields.size())
            throw IoError(file_message(path, header.line,
                                       std::string("the header has no '") + name + "' column"));
    const std::size_t needed = std::max(file_column, class_column) + 1;
    const fs::path base = fs::path(path).parent_path();
    TestSet set;
    set.path = path;
    for (std::size_t r = 1; r < records.size(); ++r) {
        const CsvRecord& record = records[r];
        if (record.fields.size() < needed)
            throw IoError(file_message(path, record.line,
                                       std::to_string(record.fields.size()) +
                                           " fields, the header needs at least " +
                                           std::to_string(needed)));
        TestSample sample;
        sample.line = record.line;
        const std::string file = trim(record.fields[file_column]);
        sample.class_name = trim(record.fields[class_column]);
        if (file.empty()) throw IoError(file_message(path, record.line, "empty file"));
        if (sample.class_name.empty())
            throw IoError(file_message(path, record.line, "empty class for " + file));
        const fs::path p(file);
        sample.file = p.is_absolute() || base.empty() ? file : (base / p).string();
        set.samples.push_back(std::move(sample));
    }
    return set;
}

TestSet read_test_set(const std::string& csv) {
    std::ifstream in(csv, std::ios::binary);
    if (!in) throw IoError(file_message(csv, 0, "cannot open test set"));
    return read_test_set(in, csv);
}

// ---- metrics --------------------------------------------------------------------------------

EvaluationReport evaluate(std::span<const QueryOutcome> outcomes, std::size_t k,
                          std::span<const std::string> classes) {
    if (k == 0) throw std::invalid_argument("evaluate: k must be >= 1");
    std::map<std::string, std::size_t> column;
    EvaluationReport report;
    report.k = k;
    for (const std::string& c : classes) {
        if (c.empty()) throw std::invalid_argument("evaluate: an empty class name");
        if (!column.emplace(c, column.size()).second)
            throw std::invalid_argument("evaluate: class '" + c + "' given twice");
        report.confusion_columns.push_back(c);
    }
    std::map<std::string, ClassTally> tallies;
    std::map<std::string, std::size_t> skipped;
    std::vector<std::size_t> ranks(k + 1, 0);
    struct Prediction {
        std::string true_class, predicted;
    };
    std::vector<Prediction> predictions;
    for (std::size_t q = 0; q < outcomes.size(); ++q) {
        const QueryOutcome& o = outcomes[q];
        if (!column.count(o.true_class)) {
            ++skipped[o.true_class];
            continue;
        }
        ClassTally& tally = tallies[o.true_class];
        if (tally.ranks.empty()) tally.ranks.assign(k + 1, 0);
        if (!o.ok()) {
            ++tally.failed;
            report.failures.push_back({o.file, o.true_class, o.error});
            continue;
        }
        if (o.neighbours.empty())
            throw std::invalid_argument("evaluate: query " + std::to_string(q) + " (" + o.file +
                                        ") has neither neighbours nor an error");
        std::size_t rank = 0;
        for (std::size_t r = 0; r < std::min(k, o.neighbours.size()); ++r)
            if (o.neighbours[r].class_name == o.true_class) {
                rank = r + 1;
                break;
            }
        const std::string& predicted = o.neighbours.front().class_name;
        ++tally.samples;
        ++tally.ranks[rank];
        ++ranks[rank];
        if (predicted != o.true_class) ++tally.wrong[predicted];
        predictions.push_back({o.true_class, predicted});
        report.queries.push_back(
            {o.file, o.true_class, predicted, rank, o.neighbours.front().distance});
    }

    // Predicted classes outside `classes` become extra columns, sorted.
    std::set<std::string> extra;
    for (const Prediction& p : predictions)
        if (!column.count(p.predicted)) extra.insert(p.predicted);
    for (const std::string& c : extra) {
        column.emplace(c, column.size());
        report.confusion_columns.push_back(c);
    }

    report.samples = report.queries.size();
    report.failed = report.failures.size();
    report.top1_hits = ranks[1];
    for (std::size_t r = 1; r <= k; ++r) report.topk_hits += ranks[r];
    report.top1 = ratio(report.top1_hits, report.samples);
    report.topk = ratio(report.topk_hits, report.samples);
    report.rank_curve = curve_of(ranks, report.samples);
    report.class_rank_curve.assign(k, 0.0);

    std::map<std::string, std::size_t> row;
    std::size_t with_samples = 0;
    for (auto& [name, tally] : tallies) {
        ClassMetrics m;
        m.class_name = name;
        m.samples = tally.samples;
        m.failed = tally.failed;
        m.top1_hits = tally.ranks[1];
        for (std::size_t r = 1; r <= k; ++r) m.topk_hits += tally.ranks[r];
        m.top1 = ratio(m.top1_hits, m.samples);
        m.topk = ratio(m.topk_hits, m.samples);
        m.rank_curve = curve_of(tally.ranks, m.samples);
        for (const auto& [wrong, count] : tally.wrong)  // map order: ties go to the first name
            if (count > m.confused_count) {
                m.confused_with = wrong;
                m.confused_count = count;
            }
        if (m.samples) {
            ++with_samples;
            report.class_top1 += m.top1;
            report.class_topk += m.topk;
            for (std::size_t r = 0; r < k; ++r) report.class_rank_curve[r] += m.rank_curve[r];
        }
        row.emplace(name, report.confusion_rows.size());
        report.confusion_rows.push_back(name);
        report.classes.push_back(std::move(m));
    }
    if (with_samples) {
        const auto n = static_cast<double>(with_samples);
        report.class_top1 /= n;
        report.class_topk /= n;
        for (double& v : report.class_rank_curve) v /= n;
    }
    report.confusion.assign(report.confusion_rows.size() * report.confusion_columns.size(), 0);
    for (const Prediction& p : predictions)
        ++report.confusion[row.at(p.true_class) * report.confusion_columns.size() +
                           column.at(p.predicted)];
    for (const auto& [name, count] : skipped) {
        report.missing_classes.push_back({name, count});
        report.skipped += count;
    }
    return report;
}

// ---- test set -------------------------------------------------------------------------------

EvaluationReport evaluate_test_set(const Recognizer& recognizer, const TestSet& test_set,
                                   const EvaluationOptions& options) {
    if (options.k == 0) throw std::invalid_argument("evaluate_test_set: k must be >= 1");
    const int threads = resolve_threads(options.threads);
    const auto start = std::chrono::steady_clock::now();
    const RecognizerInfo& info = recognizer.info();
    const std::set<std::string> known(info.categories.begin(), info.categories.end());
    const std::size_t n = test_set.samples.size();
    std::vector<QueryOutcome> outcomes(n);
    std::vector<std::size_t> work;
    for (std::size_t i = 0; i < n; ++i) {
        outcomes[i].file = test_set.samples[i].file;
        outcomes[i].true_class = test_set.samples[i].class_name;
        if (known.count(outcomes[i].true_class)) work.push_back(i);
    }

    const KnnIndex& index = recognizer.classifier().index();
    const std::vector<ViewLabel>& labels = recognizer.classifier().labels();
    const std::size_t dim = index.dimension();
    // Per work item: seconds to read, describe and match (negative: the step did not run).
    std::vector<double> read_s(work.size(), -1.0), describe_s(work.size(), -1.0),
        match_s(work.size(), -1.0);
    ProgressCounter progress(options.progress, work.size());
    parallel_for(work.size(), threads, [&](std::size_t w) {
        QueryOutcome& outcome = outcomes[work[w]];
        auto t = std::chrono::steady_clock::now();
        Points points;
        try {
            points = read_cloud(outcome.file).points;
        } catch (const std::exception& e) {
            outcome.error = e.what();
            progress.tick();
            return;
        }
        read_s[w] = seconds_since(t);
        t = std::chrono::steady_clock::now();
        const QueryDescriptor d = recognizer.describe(points);
        describe_s[w] = seconds_since(t);
        if (!d.ok()) {
            outcome.error = d.error;
            progress.tick();
            return;
        }
        t = std::chrono::steady_clock::now();
        std::vector<KnnNeighbour> all;
        for (std::size_t s = 0; s + dim <= d.signatures.size(); s += dim) {
            KnnResult r =
                index.search(std::span<const float>(d.signatures).subspan(s, dim), options.k);
            all.insert(all.end(), r.neighbours.begin(), r.neighbours.end());
        }
        std::vector<KnnNeighbour> nearest =
            d.signatures.size() == dim
                ? all
                : detail::merge_signature_neighbours(std::move(all), options.k, index,
                                                     [](std::uint32_t) { return true; });
        if (recognizer.verifies() && !nearest.empty()) {
            // The best-fitting candidate first (Recognizer::verify), the others in order.
            Classification c = classify_neighbours(nearest, labels);
            c.shape_contrast = recognizer.shape_contrast(d.signatures);
            try {
                recognizer.verify(c, Observation{drop_non_finite(points).points, nullptr});
            } catch (const std::exception& e) {
                outcome.error = e.what();
                progress.tick();
                return;
            }
            const auto first =
                std::find_if(nearest.begin(), nearest.end(), [&](const KnnNeighbour& candidate) {
                    return candidate.view == c.neighbours.front().index;
                });
            if (first != nearest.end()) std::rotate(nearest.begin(), first, first + 1);
        }
        match_s[w] = seconds_since(t);
        outcome.neighbours = outcome_neighbours(nearest, labels);
        progress.tick();
    });

    EvaluationReport report = evaluate(outcomes, options.k, info.categories);
    report.mode = "test set";
    report.database = info.database;
    report.test_set = test_set.path;
    report.descriptor = info.setup.kind.name;
    report.weighted = info.weighted;
    report.threads = threads;
    auto mean_ms = [](const std::vector<double>& s) {
        double sum = 0.0;
        std::size_t count = 0;
        for (const double v : s)
            if (v >= 0.0) {
                sum += v;
                ++count;
            }
        return count ? 1000.0 * sum / static_cast<double>(count) : 0.0;
    };
    report.read_ms = mean_ms(read_s);
    report.describe_ms = mean_ms(describe_s);
    report.match_ms = mean_ms(match_s);
    report.total_seconds = seconds_since(start);
    return report;
}

// ---- synthetic ------------------------------------------------------------------------------

namespace detail {

LomoSetup lomo_setup(const DescriptorMatrix& matrix, const std::vector<std::string>& groups,
                     const std::string& what) {
    if (matrix.rows() == 0) throw std::invalid_argument(what + ": the matrix has no views");
    if (!groups.empty() && groups.size() != matrix.models.size())
        throw std::invalid_argument(what + ": " + std::to_string(groups.size()) + " groups for " +
                                    std::to_string(matrix.models.size()) + " models");
    if (matrix.data.size() != matrix.rows() * static_cast<std::size_t>(matrix.kind.dimension))
        throw std::invalid_argument(
            what + ": the matrix holds " + std::to_string(matrix.data.size()) + " floats for " +
            std::to_string(matrix.rows()) + " rows of " + std::to_string(matrix.kind.dimension));
    // Group ids by name (ordered map: ids do not depend on the model order beyond the names).
    std::vector<std::uint32_t> model_group(matrix.models.size());
    std::map<std::string, std::uint32_t> ids;
    for (std::size_t m = 0; m < matrix.models.size(); ++m) {
        const std::string name = groups.empty() ? std::to_string(m) : std::string("g:") + groups[m];
        model_group[m] = ids.emplace(name, static_cast<std::uint32_t>(ids.size())).first->second;
    }
    LomoSetup setup;
    std::uint32_t model_number = 0;  // models in row order, numbered densely
    setup.row_views.resize(matrix.rows());
    setup.group_views.assign(ids.size(), 0);
    for (std::size_t r = 0; r < matrix.rows(); ++r) {
        const DescriptorRow& row = matrix.row_info[r];
        if (row.model >= matrix.models.size())
            throw std::invalid_argument(what + ": row " + std::to_string(r) + " has model " +
                                        std::to_string(row.model) + " of " +
                                        std::to_string(matrix.models.size()));
        if (continues_view(matrix, r)) {
            setup.multi_signature = true;
        } else {
            setup.view_first_row.push_back(r);
            setup.view_category.push_back(row.category);
            setup.view_group.push_back(model_group[row.model]);
            if (setup.view_model.empty() || row.model != matrix.row_info[r - 1].model)
                model_number = setup.view_model.empty() ? 0 : model_number + 1;
            setup.view_model.push_back(model_number);
            ++setup.group_views[model_group[row.model]];
        }
        setup.row_views[r] = static_cast<std::uint32_t>(setup.view_category.size() - 1);
    }
    setup.view_first_row.push_back(matrix.rows());
    setup.occluded_copies = setup.multi_signature && has_occluded_copies(matrix);
    std::size_t used = 0;
    for (const std::size_t v : setup.group_views) used += v > 0;
    if (used < 2)
        throw std::invalid_argument(what + ": the views belong to " + std::to_string(used) +
                                    " group; leaving one out needs at least two");
    return setup;
}

bool has_occluded_copies(const DescriptorMatrix& matrix) {
    const std::vector<std::string> names = descriptor_names();
    if (std::find(names.begin(), names.end(), matrix.kind.name) == names.end() ||
        descriptor_info(matrix.kind.name).multi_signature)
        return false;
    for (std::size_t r = 1; r < matrix.rows(); ++r)
        if (continues_view(matrix, r)) return true;
    return false;
}

DescriptorMatrix own_view_signatures(const DescriptorMatrix& matrix) {
    DescriptorMatrix out;
    out.kind = matrix.kind;
    out.categories = matrix.categories;
    out.models = matrix.models;
    const auto dim = static_cast<std::size_t>(matrix.kind.dimension);
    for (std::size_t r = 0; r < matrix.rows(); ++r) {
        if (continues_view(matrix, r)) continue;
        out.row_info.push_back(matrix.row_info[r]);
        out.data.insert(out.data.end(), matrix.data.begin() + static_cast<std::ptrdiff_t>(r * dim),
                        matrix.data.begin() + static_cast<std::ptrdiff_t>((r + 1) * dim));
    }
    return out;
}

std::vector<std::size_t> lomo_queries(std::size_t views, std::size_t max_queries) {
    std::vector<std::size_t> out;
    if (max_queries == 0 || max_queries >= views) {
        out.resize(views);
        for (std::size_t v = 0; v < views; ++v) out[v] = v;
        return out;
    }
    out.reserve(max_queries);
    for (std::size_t i = 0; i < max_queries; ++i)
        out.push_back(
            static_cast<std::size_t>(static_cast<unsigned long long>(i) * views / max_queries));
    return out;
}

KnnIndex lomo_index(const DescriptorMatrix& matrix, const LomoSetup& setup,
                    std::vector<float> weights, int threads, bool per_model) {
    KnnIndexOptions options;
    options.weights = std::move(weights);
    if (per_model) options.view_families = setup.view_model;
    options.threads = threads;
    options.sketch_group = descriptor_sketch_group(matrix.kind.name);
    const auto dim = static_cast<std::size_t>(matrix.kind.dimension);
    return setup.multi_signature ? KnnIndex(matrix.data, dim, setup.row_views, options)
                                 : KnnIndex(matrix.data, dim, options);
}

std::vector<KnnNeighbour> lomo_search(const KnnIndex& index, const LomoSetup& setup,
                                      std::size_t query, std::size_t k) {
    const std::uint32_t group = setup.view_group[query];
    const std::size_t wanted = std::min(k + setup.group_views[group], index.views());
    auto keep = [&](std::uint32_t view) { return setup.view_group[view] != group; };
    const std::size_t first = setup.view_first_row[query];
    const std::size_t last = setup.occluded_copies ? first + 1 : setup.view_first_row[query + 1];
    if (last - first == 1) {
        const KnnResult r = index.search(index.row(first), wanted);
        std::vector<KnnNeighbour> out;
        out.reserve(k);
        for (const KnnNeighbour& n : r.neighbours)
            if (keep(n.view) && out.size() < k) out.push_back(n);
        return out;
    }
    std::vector<KnnNeighbour> all;
    for (std::size_t row = first; row < last; ++row) {
        const KnnResult r = index.search(index.row(row), wanted);
        all.insert(all.end(), r.neighbours.begin(), r.neighbours.end());
    }
    return merge_signature_neighbours(std::move(all), k, index, keep);
}

}  // namespace detail

std::vector<std::string> model_groups(const DescriptorMatrix& matrix, const Catalog& catalog) {
    std::vector<std::string> out;
    out.reserve(matrix.models.size());
    for (const ModelInfo& m : matrix.models) {
        const CatalogEntry* entry = catalog.find(m.file);
        out.push_back(entry && !entry->group.empty() ? "group:" + entry->group
                                                     : "model:" + m.category + "/" + m.name);
    }
    return out;
}

std::vector<std::string> stored_model_groups(const DescriptorMatrix& matrix) {
    std::vector<std::string> out;
    out.reserve(matrix.models.size());
    for (const ModelInfo& m : matrix.models)
        out.push_back(m.group.empty() ? "model:" + m.category + "/" + m.name : "group:" + m.group);
    return out;
}

namespace {

/// The report of a synthetic evaluation from its outcomes and per-query match times.
EvaluationReport synthetic_report(std::span<const QueryOutcome> outcomes,
                                  const DescriptorMatrix& matrix, const SyntheticOptions& options,
                                  const std::string& test_set, int threads,
                                  const std::vector<double>& match_s,
                                  std::chrono::steady_clock::time_point start) {
    EvaluationReport report = evaluate(outcomes, options.k, matrix.categories);
    report.mode = "synthetic";
    report.test_set = test_set;
    report.descriptor = matrix.kind.name;
    report.weighted = !options.weights.empty();
    report.threads = threads;
    double sum = 0.0;
    for (const double s : match_s) sum += s;
    report.match_ms = match_s.empty() ? 0.0 : 1000.0 * sum / static_cast<double>(match_s.size());
    report.total_seconds = seconds_since(start);
    return report;
}

}  // namespace

EvaluationReport evaluate_synthetic(const DescriptorMatrix& matrix,
                                    const SyntheticOptions& options) {
    const std::string what = "evaluate_synthetic";
    if (options.k == 0) throw std::invalid_argument(what + ": k must be >= 1");
    const int threads = resolve_threads(options.threads);
    const auto start = std::chrono::steady_clock::now();
    const detail::LomoSetup setup = detail::lomo_setup(matrix, options.groups, what);
    const KnnIndex index =
        detail::lomo_index(matrix, setup, options.weights, threads, options.one_view_per_model);
    const std::vector<std::size_t> queries =
        detail::lomo_queries(setup.views(), options.max_queries);

    std::vector<QueryOutcome> outcomes(queries.size());
    std::vector<double> match_s(queries.size(), 0.0);
    ProgressCounter progress(options.progress, queries.size());
    parallel_for(queries.size(), threads, [&](std::size_t q) {
        const std::size_t view = queries[q];
        const DescriptorRow& row = matrix.row_info[setup.view_first_row[view]];
        QueryOutcome& o = outcomes[q];
        o.file = matrix.categories[row.category] + "/" + matrix.models[row.model].name + "#" +
                 std::to_string(row.view_index);
        o.true_class = matrix.categories[row.category];
        const auto t = std::chrono::steady_clock::now();
        const std::vector<KnnNeighbour> nearest =
            detail::lomo_search(index, setup, view, options.k);
        match_s[q] = seconds_since(t);
        o.neighbours.reserve(nearest.size());
        for (const KnnNeighbour& n : nearest)
            o.neighbours.push_back({matrix.categories[setup.view_category[n.view]], n.distance});
        if (o.neighbours.empty()) o.error = "no views outside its group";
        progress.tick();
    });

    return synthetic_report(outcomes, matrix, options,
                            options.groups.empty() ? "leave-one-model-out" : "leave-one-group-out",
                            threads, match_s, start);
}

EvaluationReport evaluate_held_out(const DescriptorMatrix& matrix,
                                   const DescriptorMatrix& all_queries,
                                   const std::vector<std::string>& query_groups,
                                   const SyntheticOptions& options) {
    const std::string what = "evaluate_held_out";
    if (options.k == 0) throw std::invalid_argument(what + ": k must be >= 1");
    // A view of the database may hold several signatures (occluded copies: the index takes
    // the nearest); a query is one row: a view's own signature, where the others are copies.
    const DescriptorMatrix queries = detail::has_occluded_copies(all_queries)
                                         ? detail::own_view_signatures(all_queries)
                                         : all_queries;

    if (matrix.kind.name != queries.kind.name || matrix.kind.dimension != queries.kind.dimension)
        throw std::invalid_argument(what + ": queries hold " + queries.kind.name +
                                    " descriptors, the database " + matrix.kind.name);
    const int threads = resolve_threads(options.threads);
    const auto start = std::chrono::steady_clock::now();
    const detail::LomoSetup setup = detail::lomo_setup(matrix, options.groups, what);
    bool multi_signature_queries = false;
    for (std::size_t r = 1; r < queries.rows(); ++r)
        multi_signature_queries |= detail::continues_view(queries, r);
    if (multi_signature_queries || queries.rows() == 0)
        throw std::invalid_argument(what + ": needs queries of one signature per view, and some");
    const KnnIndex index =
        detail::lomo_index(matrix, setup, options.weights, threads, options.one_view_per_model);
    // Group ids of the database's models by name, so a query's group is found by its name.
    // Without groups a model is its own group, named "category/name" in both matrices.
    const auto model_keys = [](const DescriptorMatrix& m) {
        std::vector<std::string> keys;
        for (const auto& model : m.models) keys.push_back(model.category + "/" + model.name);
        return keys;
    };
    const std::vector<std::string> names =
        options.groups.empty() ? model_keys(matrix) : options.groups;
    std::map<std::string, std::uint32_t> group_id;
    for (std::size_t r = 0; r < matrix.rows(); ++r)
        group_id.emplace(names[matrix.row_info[r].model], setup.view_group[setup.row_views[r]]);
    if (!query_groups.empty() && query_groups.size() != queries.models.size())
        throw std::invalid_argument(what + ": " + std::to_string(query_groups.size()) +
                                    " query groups for " + std::to_string(queries.models.size()) +
                                    " models");
    const std::vector<std::string> query_names =
        query_groups.empty() ? model_keys(queries) : query_groups;
    const std::vector<std::size_t> picked =
        detail::lomo_queries(queries.rows(), options.max_queries);
    std::vector<QueryOutcome> outcomes(picked.size());
    std::vector<double> match_s(picked.size(), 0.0);
    ProgressCounter progress(options.progress, picked.size());
    parallel_for(picked.size(), threads, [&](std::size_t q) {
        const DescriptorRow& row = queries.row_info[picked[q]];
        QueryOutcome& o = outcomes[q];
        o.file = queries.categories[row.category] + "/" + queries.models[row.model].name + "#" +
                 std::to_string(row.view_index);
        o.true_class = queries.categories[row.category];
        const auto it = group_id.find(query_names[row.model]);
        const std::size_t excluded = it == group_id.end() ? 0 : setup.group_views[it->second];
        const auto t = std::chrono::steady_clock::now();
        const KnnResult found =
            index.search(queries.row(picked[q]), std::min(options.k + excluded, index.views()));
        match_s[q] = seconds_since(t);
        for (const KnnNeighbour& n : found.neighbours) {
            if (it != group_id.end() && setup.view_group[n.view] == it->second) continue;
            if (o.neighbours.size() == options.k) break;
            o.neighbours.push_back({matrix.categories[setup.view_category[n.view]], n.distance});
        }
        if (o.neighbours.empty()) o.error = "no views outside its group";
        progress.tick();
    });
    return synthetic_report(outcomes, matrix, options, "held-out views", threads, match_s, start);
}

}  // namespace esf
