#pragma once
// Evaluation (Wohlkinger & Vincze 2011, Sec. V): how often the nearest training views of a query
// have its true class, overall and per class, on labelled real clouds (a test set) or on the
// database's own synthetic views, leave-one-model-out.
//
//   test set:  TESTSET.csv (file, class) -> read_cloud -> describe (the database's settings)
//              -> k nearest views (L1, learned weights when stored) -> QueryOutcome per row
//   synthetic: every view of every model is a query against the views of all OTHER models
//              (or all other groups: models sharing a shape group are left out together)
//   outcomes -> evaluate(): 1-NN and k-NN accuracy per sample and per class, the most confused
//              class (the paper's Table I), a confusion matrix and rank curves (Figs. 15-18).
//
// Neighbours: by default the k nearest models, each by its nearest view (one view per model;
// RecognizerOptions / SyntheticOptions::one_view_per_model), so the ten nearest are ten models
// rather than ten views of one or two; with one_view_per_model = false the k nearest views (the
// paper's ranks). The 1-NN is the same either way.
//
// Definitions (k = EvaluationReport::k):
//   rank of a query   1-based position of the first of its k nearest views whose class is the
//                     query's true class; 0 when none of them has it
//   top-1 (1-NN)      share of the queries of rank 1: the nearest view has the true class
//   top-k (k-NN)      share of the queries of rank 1..k: the true class is among the classes of
//                     the k nearest views (not the vote of Classifier)
//   rank curve        curve[r - 1] = share of the queries of rank 1..r, r = 1..k
//   per class         the same over the queries of one true class; class_top1 / class_topk /
//                     class_rank_curve are the means over the classes with at least one query
//   confused with     the most frequent wrong 1-NN class of a class's queries (ties: the
//                     alphabetically first), empty when none was wrong
// Queries whose class is not a class of the database are skipped (counted per class, not
// fatal); queries that could not be read or described are failed (listed with their errors).
// Neither counts in any accuracy.
//
// Exactness: evaluate_synthetic() returns exactly what a brute-force search over the views of
// the other groups returns (same views, same order, same distances), as KnnIndex does; a
// multi-signature view's distance is the minimum over pairs of signatures, as in Recognizer.
// Every result is independent of the thread count; only the timings vary from run to run.
//
// Thread safety: all functions are reentrant; evaluate_test_set() may run concurrently on one
// Recognizer (its members are const).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <istream>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "esf/recognition/recognizer.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"

namespace esf {

// ---- test sets ------------------------------------------------------------------------------

/// One labelled cloud of a test set.
struct TestSample {
    std::string file;        ///< path resolved against the CSV's folder (absolute kept as is)
    std::string class_name;  ///< the `class` column
    std::size_t line = 0;    ///< line of the CSV it came from (1 = the header)
};

struct TestSet {
    std::string path;  ///< the CSV
    std::vector<TestSample> samples;
};

/// Reads a test set CSV: a header row naming at least the columns `file` and `class` (any
/// order, case-insensitive, surrounding spaces ignored; other columns are ignored), then one row
/// per cloud. RFC 4180 quoting (fields in double quotes may hold commas, line breaks and "" for a
/// quote), LF or CRLF line ends, blank lines skipped. `file` is resolved relative to the CSV's
/// folder unless absolute. Throws esf::IoError "path:line: reason" for an unreadable file, a
/// missing column, an unterminated quote, a row with fewer fields than the header needs, or an
/// empty file or class.
TestSet read_test_set(const std::string& csv);
/// As above from a stream; `path` names it in messages and its folder resolves the files.
TestSet read_test_set(std::istream& in, const std::string& path);

// ---- outcomes and metrics -------------------------------------------------------------------

/// One of the nearest views of a query: its class and distance.
struct OutcomeNeighbour {
    std::string class_name;
    double distance = 0.0;
};

/// What happened to one query: its true class and its nearest views (nearest first), or why it
/// has none.
struct QueryOutcome {
    std::string file;        ///< what the query is (a path, or "category/model#view")
    std::string true_class;  ///< its label
    std::vector<OutcomeNeighbour> neighbours;  ///< nearest first; only the first k are used
    std::string error;                         ///< non-empty: failed (no neighbours)

    bool ok() const { return error.empty(); }
};

/// The per-query line of a report.
struct QueryResult {
    std::string file;
    std::string true_class;
    std::string predicted;  ///< class of the nearest view
    std::size_t rank = 0;   ///< 1..k, 0 = the true class is not among the k nearest views
    double distance = 0.0;  ///< distance of the nearest view
};

/// A query that could not be evaluated.
struct QueryFailure {
    std::string file;
    std::string true_class;
    std::string error;
};

/// Accuracy of one true class.
struct ClassMetrics {
    std::string class_name;
    std::size_t samples = 0;         ///< evaluated queries of the class
    std::size_t top1_hits = 0;       ///< of rank 1
    std::size_t topk_hits = 0;       ///< of rank 1..k
    double top1 = 0.0;               ///< top1_hits / samples
    double topk = 0.0;               ///< topk_hits / samples
    std::string confused_with;       ///< most frequent wrong 1-NN class; empty when none
    std::size_t confused_count = 0;  ///< how often it was the 1-NN class
    std::size_t failed = 0;          ///< queries of the class that failed
    std::vector<double> rank_curve;  ///< k values, see the top of the file
};

/// Queries skipped because their class is not a class of the database.
struct SkippedClass {
    std::string class_name;
    std::size_t samples = 0;
};

/// Everything an evaluation measured. Fractions are in [0, 1]; empty sets give 0.
struct EvaluationReport {
    // What was evaluated (filled by evaluate_test_set / evaluate_synthetic; free text).
    std::string mode;        ///< "test set" or "synthetic"
    std::string database;    ///< path, when known
    std::string test_set;    ///< CSV path (test set), or "leave-one-model-out" /
                             ///< "leave-one-group-out" (synthetic)
    std::string descriptor;  ///< descriptor kind name
    bool weighted = false;   ///< learned weights were applied

    std::size_t k = 10;
    std::size_t samples = 0;  ///< evaluated queries
    std::size_t top1_hits = 0;
    std::size_t topk_hits = 0;
    double top1 = 0.0;                     ///< 1-NN accuracy per sample
    double topk = 0.0;                     ///< k-NN accuracy per sample
    double class_top1 = 0.0;               ///< mean over classes of their 1-NN accuracy
    double class_topk = 0.0;               ///< mean over classes of their k-NN accuracy
    std::vector<double> rank_curve;        ///< per sample, k values
    std::vector<double> class_rank_curve;  ///< mean over classes, k values

    /// Classes with at least one evaluated or failed query, sorted by name.
    std::vector<ClassMetrics> classes;

    /// Confusion matrix: rows = the names of `classes` (true class), columns = the database's
    /// classes (predicted 1-NN class), counts row-major (rows x columns).
    std::vector<std::string> confusion_rows;
    std::vector<std::string> confusion_columns;
    std::vector<std::size_t> confusion;
    std::size_t confusion_at(std::size_t row, std::size_t column) const {
        return confusion[row * confusion_columns.size() + column];
    }

    std::size_t skipped = 0;                    ///< queries of classes not in the database
    std::vector<SkippedClass> missing_classes;  ///< those classes, sorted by name
    std::size_t failed = 0;                     ///< queries that could not be evaluated
    std::vector<QueryFailure> failures;         ///< in query order

    std::vector<QueryResult> queries;  ///< evaluated queries, in query order

    // Timings (evaluate_test_set, evaluate_synthetic); 0 where not measured.
    double read_ms = 0.0;        ///< mean wall time to read one cloud
    double describe_ms = 0.0;    ///< mean wall time to describe one cloud (per descriptor)
    double match_ms = 0.0;       ///< mean wall time of one k-NN search (per match)
    double total_seconds = 0.0;  ///< wall time of the whole evaluation
    int threads = 1;             ///< threads used
};

/// Metrics of `outcomes` with `k` nearest views (>= 1; a query with fewer neighbours counts as
/// missing the true class beyond them). `classes` are the database's classes: queries of other
/// classes are skipped, and they are the columns of the confusion matrix (a neighbour of a class
/// outside `classes` adds a column at the end). Throws std::invalid_argument for k = 0, an empty
/// or repeated class in `classes`, or an outcome that is ok() without neighbours.
EvaluationReport evaluate(std::span<const QueryOutcome> outcomes, std::size_t k,
                          std::span<const std::string> classes);

/// Called as queries finish: (done, total). Calls are serialised but may come from worker
/// threads; it must not throw.
using EvaluationProgress = std::function<void(std::size_t, std::size_t)>;

struct EvaluationOptions {
    std::size_t k = 10;  ///< nearest views per query (>= 1)
    int threads = 0;     ///< 0 = all cores
    EvaluationProgress progress;
};

/// Evaluates a test set against a recognizer's database: each sample whose class is a class of
/// the database is read (esf::read_cloud), described with the database's descriptor and
/// settings (Recognizer::describe), and searched for its options.k nearest views in the
/// recognizer's index (its weights; a multi-signature query takes the minimum over its
/// signatures, as Recognizer does). A file that cannot be read or described is a failure, not an
/// error. Samples run in parallel, one cloud in memory per thread; timings are per cloud.
/// Throws std::invalid_argument for k = 0 or negative threads.
EvaluationReport evaluate_test_set(const Recognizer& recognizer, const TestSet& test_set,
                                   const EvaluationOptions& options = {});

struct SyntheticOptions {
    std::size_t k = 10;  ///< nearest views per query (>= 1)
    /// Per-dimension weights of the L1 distance (finite, >= 0; empty = all 1). For ESF's ten
    /// block weights use expand_block_weights(weights, kEsfBins).
    std::vector<float> weights;
    /// Group of each model of the matrix (matrix.models order): the views of a query's group
    /// are left out of its search. Empty: each model is its own group (leave-one-model-out).
    /// See model_groups().
    std::vector<std::string> groups;
    /// Queries: 0 = every view; otherwise at most this many views, evenly spaced over the
    /// matrix's view order (view floor(i * views / max_queries)), so the subset is deterministic.
    std::size_t max_queries = 0;
    /// The k nearest models, each by its nearest view (as Recognizer does by default); false:
    /// the k nearest views, several of one model among them (the paper's ranks).
    bool one_view_per_model = true;
    int threads = 0;  ///< 0 = all cores
    EvaluationProgress progress;
};

/// The group of each model of `matrix` (matrix.models order) from a catalog (read_catalog):
/// the `group` of the entry whose `file` is the model's file; a model without entry, or with an
/// empty group, is its own group. Without a catalog, stored_model_groups() uses the groups the
/// database stored at training.
std::vector<std::string> model_groups(const DescriptorMatrix& matrix, const Catalog& catalog);
/// The groups stored with the models (ModelInfo::group), a model's name where empty.
std::vector<std::string> stored_model_groups(const DescriptorMatrix& matrix);

/// Leave-one-model-out (or leave-one-group-out) evaluation over a database's own views: every
/// query view (options.max_queries) is searched against the views of all models of other groups,
/// by the exact (weighted) L1 distance, k nearest kept; the true class is the view's category.
/// Views are (model, view index) pairs; consecutive rows of one view are its signatures. The
/// search is one KnnIndex over all views, asked for k + (views of the query's group) neighbours
/// per query signature, minus the query's group: exact (see the top of the file).
/// Throws std::invalid_argument for k = 0, bad weights (size, non-finite, negative), a groups
/// vector whose size is not the number of models, or a matrix without views or with fewer than
/// two groups.
EvaluationReport evaluate_synthetic(const DescriptorMatrix& matrix,
                                    const SyntheticOptions& options = {});

/// Held-out synthetic queries: every view of `queries` (another database's views of the same
/// models, e.g. rendered with another seed, other cameras and distances) is searched among the
/// views of `matrix` whose model belongs to another group than the query's model, by the exact
/// (weighted) L1 distance; the true class is the query's category. So databases trained with
/// different cameras are compared on the same queries. `groups` names the group of each model
/// of `matrix`, `query_groups` of each model of `queries` (models order; when empty, each model
/// is its own group, matched by "category/name": leave-one-model-out). Both matrices must hold the
/// same descriptor and dimension; a view of `matrix` may hold several signatures (occluded copies:
/// its nearest counts), a view of `queries` one. Throws std::invalid_argument for k = 0, bad
/// weights, group vectors of the wrong size, multi-signature queries, empty matrices, or matrices
/// of other kinds.
EvaluationReport evaluate_held_out(const DescriptorMatrix& matrix, const DescriptorMatrix& queries,
                                   const std::vector<std::string>& query_groups,
                                   const SyntheticOptions& options = {});

}  // namespace esf
