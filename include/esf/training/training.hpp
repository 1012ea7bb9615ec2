#pragma once
// Training (the paper's Sec. IV): every CAD model of ROOT/<category>/<model>.<ext> is rendered
// from the view sphere, every view is described with ESF (or, for the baseline comparison, any
// descriptor of descriptor.hpp), and the views, descriptors and the settings used go into a
// Database, one transaction per model.
//
// The rendering does not depend on the descriptor: databases of different descriptors trained
// with the same seed and render options hold the same views (poses, point counts, sensor noise),
// so descriptors are compared on identical data.
//
// Resuming: models already complete in the database are skipped, so a run that was killed
// continues where it stopped and a root with new models only adds those. Seeds are derived from
// (seed, category/model name, view index), so the stored data does not depend on the thread
// count, on the order models are trained in, or on which models were trained before.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "esf/descriptors/descriptor.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/render/render.hpp"
#include "esf/training/database.hpp"

namespace esf {

/// A mesh file found under a training root.
struct ModelFile {
    std::string category;  ///< the folder name
    std::string name;      ///< the file name without extension
    std::string file;      ///< path relative to the root, '/'-separated ("box/kit_Amicelli.obj")
    std::string path;      ///< full path
};

/// File extensions find_models() takes as meshes (lower case; matched case-insensitively).
const std::vector<std::string>& mesh_extensions();

/// Lists ROOT/<category>/<model>.<ext> for the mesh extensions, sorted by (category, name).
/// Hidden files and folders, files directly in ROOT and deeper folders are ignored. Throws
/// esf::IoError when ROOT is not a folder, std::invalid_argument when two files of a category
/// share a name (e.g. mug/a.ply and mug/a.obj).
std::vector<ModelFile> find_models(const std::string& root);

/// One row of a mesh catalog: `file,category,source,model,group,extent,metric,...` with `file`
/// relative to the training root, `extent` the longest side of the model's oriented bounding box
/// in file units and `metric` "yes" or "no".
struct CatalogEntry {
    std::string file;
    std::string category;
    std::string group;
    double extent = 0.0;  ///< 0: unknown
    bool metric = true;
};

struct Catalog {
    std::vector<CatalogEntry> entries;

    /// The entry of a file (relative path as in ModelFile::file), nullptr when absent.
    const CatalogEntry* find(const std::string& file) const;
};

/// Reads a catalog CSV (RFC 4180 quoting; columns found by header name, `file` required).
/// Throws esf::IoError "path:line: reason" for unreadable files and malformed rows.
Catalog read_catalog(const std::string& path);

/// The size (longest side, metres) given to a non-metric model of `category`: the median extent
/// of the catalog's metric models of that category; for categories without any, a table of
/// typical household object sizes (e.g. glass 0.12 m, spray 0.20 m, tube 0.17 m); otherwise
/// kDefaultTypicalExtent.
double typical_extent(const Catalog& catalog, const std::string& category);
inline constexpr double kDefaultTypicalExtent = 0.15;

/// Which models of a root a run takes, by their catalog group (a model without a catalog entry,
/// or with an empty group, is a group of its own named after the model). Evaluation on models a
/// database does not hold takes the same selection both ways: `esf generate-scenes --fold 0/3`
/// and `esf train --other-folds 0/3` see disjoint groups.
struct GroupSelection {
    std::vector<std::string> only;    ///< non-empty: only these groups
    std::vector<std::string> except;  ///< never these groups
    /// Non-empty: only the models of these categories. Folds are dealt as without it (each
    /// category's groups on their own), so a fold keeps its groups whatever categories are taken.
    std::vector<std::string> categories;
    /// With folds > 1: the groups of each category are dealt into `folds` folds in an order
    /// fixed by a hash of their names (so every fold holds groups of most categories); a
    /// category with a single group is in no fold (it stays on the training side). `fold` in
    /// [0, folds) takes that fold's groups; with other_folds, every group but them.
    int fold = 0;
    int folds = 0;
    bool other_folds = false;

    bool empty() const {
        return only.empty() && except.empty() && categories.empty() && folds <= 1;
    }
};

/// Parses "K/N" (fold K of N, 0 <= K < N, 2 <= N <= 100) into selection.fold / folds; throws
/// std::invalid_argument naming the text otherwise.
void parse_fold(const std::string& text, GroupSelection& selection);

/// A model as a run takes it: its file, its group and how it is scaled to metres.
struct PlannedModel {
    ModelFile file;
    std::string group;           ///< catalog group, or the model's name
    bool rescale = false;        ///< non-metric: scaled to target_extent
    double extent = 0.0;         ///< catalog extent (file units); 0: the mesh's bounding box
    double target_extent = 0.0;  ///< metres
    /// The file units -> metres factor for `mesh`: target_extent / extent when rescaled (the
    /// mesh's longest bounding box side standing in for an unknown extent), else
    /// `metric_scale`. Throws std::invalid_argument for a mesh without extent.
    double scale(const Mesh& mesh, double metric_scale = 1.0) const;
};

/// The models under `root` (find_models) with their catalog groups and scaling, those of
/// `selection` only. `catalog`: a catalog CSV, or empty for ROOT/catalog.csv when it exists;
/// use_catalog false ignores any. Throws like find_models and read_catalog, and
/// std::invalid_argument when a group named in `selection` is not among the root's.
std::vector<PlannedModel> plan_models(const std::string& root, const std::string& catalog,
                                      bool use_catalog, const GroupSelection& selection);

/// Seed of a model's rendering, derived from the run's seed and "category/name".
std::uint64_t model_seed(std::uint64_t seed, const std::string& category, const std::string& name);
/// Seed of the descriptor of one view of a model.
std::uint64_t view_seed(std::uint64_t model_seed, int view_index);

struct TrainingProgress {
    std::size_t models_total = 0;     ///< models found under the root
    std::size_t models_done = 0;      ///< handled so far, including those already stored
    std::size_t models_existing = 0;  ///< already complete in the database (not redone)
    std::size_t models_failed = 0;
    std::size_t views = 0;          ///< views described in this run
    std::size_t views_skipped = 0;  ///< views skipped in this run
    std::string model;              ///< "category/name" just finished; empty in the first call
};

/// Camera distances of training views by default (metres from the model's centre): each view's
/// distance is drawn from [kTrainingCameraDistance, kTrainingMaxCameraDistance], where a depth
/// sensor looking at a table top sees it from (Kinect v1 works from 0.5 m; table scenes are
/// taken at 0.6 to 1.2 m). The point density and the sensor noise of the views then match what
/// the real sensor gives; an object in the image's middle half, as with PCL's renderer, is seen
/// from far closer and with little noise (see BENCHMARKS.md for the effect on accuracy).
inline constexpr double kTrainingCameraDistance = 0.6;
inline constexpr double kTrainingMaxCameraDistance = 1.2;
/// Lowest camera elevation of training views by default (degrees above the model's xy plane):
/// objects stand on a table and are seen from above, so the cameras below the model's
/// horizontal plane (meshes are stored z up) are left out.
inline constexpr double kTrainingMinElevation = 0.0;
/// A model whose bounding sphere radius exceeds the camera distance / this factor is seen from
/// that factor times its radius instead (it would not fit the image otherwise).
inline constexpr double kTrainingMinDistanceFactor = 1.5;
/// The descriptor training stores by default: ESF with the surface angle histograms.
inline constexpr const char* kTrainingDescriptor = "esf-angles";
/// Surface samples stored per model for verification.
inline constexpr std::size_t kTrainingSurfacePoints = 2000;
/// Occluded copies of each training view (TrainingOptions::occlusions; BENCHMARKS.md, "Training
/// views with part hidden").
inline constexpr std::size_t kTrainingOcclusions = 3;
inline constexpr std::size_t kMaxTrainingOcclusions = 16;

/// The render options training uses by default: RenderOptions with the cameras of the upper
/// half of the view sphere (kTrainingMinElevation) at kTrainingCameraDistance to
/// kTrainingMaxCameraDistance.
inline RenderOptions default_training_render() {
    RenderOptions render;
    render.distance = kTrainingCameraDistance;
    render.max_distance = kTrainingMaxCameraDistance;
    render.min_elevation = kTrainingMinElevation;
    return render;
}

struct TrainingOptions {
    /// View sphere, camera and sensor. render.seed is ignored (see model_seed), render.threads
    /// too (see `threads`); render.scale / target_extent apply to every model except the
    /// non-metric ones of a catalog, which get typical_extent() of their category. With
    /// render.distance set, a model larger than render.distance / kTrainingMinDistanceFactor
    /// is seen from kTrainingMinDistanceFactor times its bounding sphere radius; without it,
    /// the distance follows render.fill_fraction (render.max_distance is scaled with it).
    RenderOptions render = default_training_render();
    /// The descriptor stored: "esf" (our estimator with `esf`) or any other name of
    /// descriptor_names() (make_descriptor() with `descriptor_options`).
    std::string descriptor = kTrainingDescriptor;
    EsfOptions esf;  ///< descriptor "esf" only; esf.seed is ignored (see view_seed)
    /// Any other descriptor, the default esf-angles included (its ESF part takes
    /// descriptor_options.samples); descriptor_options.seed is ignored (see view_seed).
    DescriptorOptions descriptor_options;
    std::uint64_t seed = 0;
    /// Views with fewer points (e.g. a thin object seen edge-on) are stored as skipped.
    std::size_t min_points = 50;
    /// Each view is also described this many times with part of it hidden (occlude_view(), an
    /// edge of occlusion_edge() from the view's seed; a copy left with fewer than min_points
    /// points is not described): one more signature of the view each, so that a query's
    /// distance to the view is the smallest to any of them. The view's own signature comes
    /// first. Descriptors of several signatures a cloud (CVFH, OUR-CVFH) get none. 0: the view's
    /// own signature alone. At most kMaxTrainingOcclusions.
    std::size_t occlusions = kTrainingOcclusions;
    /// Samples of each model's surface stored for verification (sample_model_surface(), the
    /// model's seed); 0 stores none (recognition then verifies only with the meshes at hand).
    std::size_t surface_points = kTrainingSurfacePoints;
    int threads = 0;  ///< 0 = all cores
    /// Catalog CSV; empty: ROOT/catalog.csv when it exists. With a catalog, non-metric models are
    /// scaled so their extent is typical_extent() of their category, and models get its group.
    std::string catalog;
    bool use_catalog = true;  ///< false: ignore any catalog (all models metric, group = name)
    /// The models trained (plan_models); models of a database outside it stay as they are.
    GroupSelection groups;
    /// Called on the calling thread once before the first model and after every model committed.
    /// It may throw to stop training: models committed so far stay, the exception propagates.
    std::function<void(const TrainingProgress&)> progress;
};

struct TrainingFailure {
    std::string model;  ///< "category/name"
    std::string error;
};

struct TrainingResult {
    std::size_t models_total = 0;
    std::size_t models_trained = 0;   ///< completed in this run
    std::size_t models_existing = 0;  ///< already complete, skipped
    std::size_t models_failed = 0;    ///< stored as failed in this run (retried on resume)
    std::size_t views = 0;            ///< described in this run
    std::size_t views_skipped = 0;    ///< skipped in this run
    std::vector<TrainingFailure> failures;
};

/// The settings train() stores with a database and compares on resume: the descriptor's name,
/// version and dimension, its options (esf_* for "esf", descriptor_* for the others, the keys
/// Recognizer's query_setup() reads), the seed, view sphere, camera, sensor and scaling. Throws
/// std::invalid_argument for an unknown descriptor.
Settings training_settings(const TrainingOptions& options, bool rescale_non_metric);

/// Trains every model under `root` that is not complete in `database` (opened for writing).
/// Throws std::invalid_argument for bad options (an unknown descriptor: the message lists the
/// valid names), for a root without meshes and when the database holds other settings (naming
/// each difference; another descriptor first); esf::IoError for unreadable roots, catalogs or
/// database errors. A mesh that fails to load or render is stored as failed, not thrown.
/// Models go in batches of 2 x threads: their meshes load in parallel, all their views are
/// rendered and described in parallel (one view per task), then they are committed in order.
/// A view the descriptor cannot describe (too few points left after a baseline's preprocessing,
/// a degenerate cloud) is stored as skipped with the descriptor's message, like a view with fewer
/// than min_points points. Multi-signature descriptors (cvfh, our-cvfh) store all signatures of
/// a view.
TrainingResult train(const std::string& root, Database& database,
                     const TrainingOptions& options = {});

}  // namespace esf
