#pragma once
// Online recognition, the right half of the paper's Fig. 1 (Wohlkinger & Vincze 2011, Sec. IV):
// a cloud or a segmented table scene in, per object the most similar class, model and view out.
//
//   database (opened read-only once) -> k-NN index over its descriptors (+ learned weights)
//   scene -> segment_scene() -> clusters -> descriptors (in parallel, the database's settings)
//         -> k nearest models, each by its nearest view (L1) -> the nearest one's class (the
//            others give the confidence), best model, view and pose
//
// A Recognizer describes queries with exactly the descriptor and settings the database was
// trained with (query_setup() reads them from the database), so query and training descriptors
// are comparable; a database made by another descriptor version, with a descriptor this build
// does not know, or with settings it cannot reproduce is refused with a message naming the file
// and the difference.
//
// Multi-signature descriptors (cvfh, our-cvfh): a view's distance is the smallest distance
// between any signature of the query and any signature of the view, as in PCL's recognition
// pipeline (pcl::rec_3d_framework::GlobalNNCVFHRecognizer). The k nearest views under that
// distance are exact: every view among them is among the k nearest of the query signature that
// attains its minimum, so the union of the per-signature searches holds them all.
//
// Thread safety: a constructed Recognizer is immutable; every member function is const and may
// run concurrently from any number of threads. Results do not depend on the thread count.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "esf/core/point_cloud.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/recognition/classifier.hpp"
#include "esf/segmentation/segmentation.hpp"
#include "esf/training/database.hpp"

namespace esf {

struct RecognizerOptions {
    std::size_t k = 10;  ///< views that vote (>= 1; fewer when the database has fewer views)
    /// The k neighbours are the k nearest models, each by its nearest view (its class, pose and
    /// distance), so that one model's many similar views do not fill the list and the vote;
    /// false: the k nearest views (the paper's ranks).
    bool one_view_per_model = true;
    /// How the neighbours name the class (classifier.hpp): the nearest one's class by default.
    VoteRule vote = VoteRule::kNearest;
    /// Descriptor kind to use when the database holds several; empty: the only one stored.
    std::string descriptor;
    /// Weigh the L1 distance with the database's learned block weights when it has them
    /// (ESF only: ten sub-histogram weights, each applied to its 64 bins).
    bool use_weights = true;
    /// Single-signature descriptors: a query is described this many times with different
    /// sampling seeds and the signatures are averaged (>= 1; a multi-signature descriptor is
    /// refused above 1). The seed-to-seed spread of one ESF is about 0.05-0.08 in L1; averaging
    /// brings the query nearer its expected histogram. Costs one description per sampling.
    int query_samplings = 1;
    int threads = 0;  ///< building the index, describing and classifying batches; 0 = all cores
    /// The SIMD kernels of description and search (EsfOptions::kernels, KnnIndexOptions::kernels):
    /// every set gives the same results; kAvx2 runs what a CPU without AVX-512 runs. A set the
    /// CPU lacks is refused (std::invalid_argument).
    Kernels kernels = Kernels::kBest;
    /// Verify every classification (esf/recognition/pose_verification.hpp): the nearest
    /// `verification.candidates` models are aligned to the points and the best fit names the
    /// class (verification.decide_class), model and 6-DoF pose. Needs each model's surface: the
    /// ones the database stores (esf train stores them), or `verification_meshes`. A database
    /// that stores none (trained before they were stored), without verification_meshes, is
    /// recognised by k-NN only (RecognizerInfo::verification says so). false: k-NN only.
    bool verify = true;
    /// Non-empty: the surfaces are sampled from the meshes of this folder, the root the database
    /// was trained from (each model's stored file and scale, sampled with its training seed: the
    /// surfaces training stores), instead of read from the database.
    /// Surfaces load once, on first use.
    std::string verification_meshes;
    VerificationOptions verification;
    /// Scenes with a frame (recognize with a frame, when verifying): two neighbouring objects
    /// (pixels at most 6 apart in a row or column, within 3 cm of each other, at 5 places or
    /// more) become one when a model fitted to both is verified, explains at least
    /// merge_min_inliers of their points and scores no less than the point-weighted mean of their
    /// own fits: an object that segmentation cut at a concave joint or a thin stem (a mug's
    /// handle, a screwdriver's shaft, a figurine's limbs, a wine glass's foot). Repeated while
    /// pairs merge. The models fitted to a pair: the nearest models of its own descriptor (as
    /// any object's), and each part's verified model from the part's pose (the model of a mug's
    /// body fits its handle too where the pair's nearest views start too far off). Chosen on
    /// generated scenes and real fold 0 (BENCHMARKS.md). false: the objects stay as segmented.
    bool merge_parts = true;
    double merge_min_inliers = 0.7;  ///< [0, 1]
};

/// How query clouds are described: what the database's descriptors were made with.
struct QuerySetup {
    DescriptorKind kind;
    /// name "esf": our estimator with the stored samples, grid size, sampler, attempt budget
    /// and seed (the training run's seed; training views each drew from one derived from it).
    EsfOptions esf;
    /// Any other descriptor (make_descriptor(kind.name, options)).
    DescriptorOptions options;
};

/// The descriptor version this build computes for `name`: stored_descriptor_version(name). Throws
/// std::invalid_argument for a name make_descriptor() does not know.
int descriptor_version(const std::string& name);

/// Reads the query setup of descriptor `kind` from a database's settings. Keys (each optional;
/// a missing key takes the default of EsfOptions / DescriptorOptions):
///   descriptor, descriptor_version, descriptor_dimension   must agree with `kind` when present
///   esf_samples, esf_grid_size, esf_sampler, esf_max_attempts_per_sample   (esf)
///   descriptor_samples, descriptor_leaf_factor, descriptor_normal_radius_factor,
///   descriptor_remove_outliers (0/1)                                        (the others)
///   descriptor_angles_weight                                                (esf-angles)
///   seed                                                                    (all)
/// Throws std::invalid_argument, naming the setting or the difference, for an unknown
/// descriptor, a version or dimension other than this build's, settings of the wrong type or
/// out of range.
QuerySetup query_setup(const Settings& settings, const DescriptorKind& kind);

/// One candidate verification fitted (Recognizer::verify's `candidates`): its neighbour, its
/// fit, and the shape term it competed with.
struct CandidateFit {
    std::size_t neighbour = 0;  ///< index into the classification's neighbours before reordering
    PoseFit fit;
    double shape_term = 0.0;
};

/// A model verified on the same object in an earlier frame (a track's last fit): verification
/// fits it first, from where it stood (VerificationOptions::prior_tolerance).
struct PriorFit {
    int model_id = -1;                                   ///< Classification::best_model_id
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();  ///< Classification::pose then
    double score = 0.0;                                  ///< its FitScore::score() then
};

/// What a Recognizer loaded.
struct RecognizerInfo {
    std::string database;  ///< path
    QuerySetup setup;
    bool weighted = false;   ///< learned weights are applied
    std::size_t views = 0;   ///< views with a descriptor (index views)
    std::size_t rows = 0;    ///< signatures (= views unless multi-signature)
    std::size_t models = 0;  ///< complete models
    std::vector<std::string> categories;
    /// How classifications are verified: "stored surfaces", "meshes of ROOT", "off", or "off:
    /// " and why (the database stores no model surfaces).
    std::string verification;
};

/// The descriptor of one query cloud: one or more signatures, or why it has none.
struct QueryDescriptor {
    std::vector<float> signatures;  ///< count x dimension floats, row-major
    std::size_t points = 0;         ///< points in the cloud (finite or not)
    std::string error;              ///< non-empty: the cloud could not be described

    bool ok() const { return error.empty(); }
};

/// Classification of one cloud of a batch: `error` says why there is none.
struct CloudClassification {
    Classification classification;  ///< valid when ok()
    std::string error;

    bool ok() const { return error.empty(); }
};

/// One object of a scene: its cluster (points, centroid, size, truncation status) and its class.
struct RecognizedObject {
    Cluster cluster;
    Classification classification;  ///< valid when classified()
    /// Why the object has no class (e.g. "esf: needs at least 3 finite points, got 2", or a
    /// degenerate cluster); empty when classified.
    std::string error;

    bool classified() const { return error.empty(); }
};

/// A recognised table scene: the segmentation's plane and message, and its objects in the
/// segmentation's order (largest first).
struct SceneRecognition {
    bool plane_found = false;
    Plane plane;
    std::size_t plane_inliers = 0;
    std::size_t finite_points = 0;
    /// For people: "no dominant plane: ...", "no objects above the plane", "3 objects above the
    /// plane".
    std::string message;
    std::vector<RecognizedObject> objects;
};

/// The frame verification checks a scene's hypotheses against (free space, outlines): `scene`
/// itself when it is the camera's image (camera.width x camera.height), else, for an unorganised
/// cloud whose points each lie on their own pixel, that image, made into `image`
/// (depth_image_of); otherwise none (nullptr). Recognizer::recognize() uses it.
const PointCloud* verification_frame(const PointCloud& scene, const CameraIntrinsics& camera,
                                     std::optional<PointCloud>& image);

class Recognizer {
  public:
    /// Opens the database read-only, loads its descriptors and weights and builds the index.
    /// Throws esf::IoError naming the file when it is missing, corrupt or not an esf database,
    /// and std::invalid_argument naming it when it holds no views, several descriptor kinds
    /// (and options.descriptor is empty), an absent kind, or settings query_setup() refuses;
    /// std::invalid_argument for k = 0 or negative threads.
    explicit Recognizer(const std::string& database, const RecognizerOptions& options = {});
    ~Recognizer();
    Recognizer(Recognizer&&) noexcept;
    Recognizer& operator=(Recognizer&&) noexcept;

    /// Describes a cloud with the database's descriptor (non-finite points are dropped first);
    /// never throws for bad clouds: the error is in the result.
    QueryDescriptor describe(std::span<const Eigen::Vector3f> points) const;
    /// Describes many clouds in parallel (options.threads).
    std::vector<QueryDescriptor> describe_batch(std::span<const Points> clouds) const;

    /// k nearest views of a descriptor (signatures.size() a positive multiple of the dimension)
    /// and their vote. Throws std::invalid_argument for a wrong size or non-finite values.
    Classification classify_descriptor(std::span<const float> signatures) const;
    /// The cylinder-box contrast of a descriptor's first signature (what verification weighs with
    /// VerificationOptions::shape_weight); NaN when the descriptor has no such block or
    /// `signatures` is shorter than one signature.
    double shape_contrast(std::span<const float> signatures) const;
    /// Classifies described clouds as one batch; failed descriptors pass their error on.
    std::vector<CloudClassification> classify_batch(
        std::span<const QueryDescriptor> descriptors) const;

    /// describe + classify_descriptor. Throws std::invalid_argument naming the descriptor for a
    /// cloud it cannot describe (fewer than 3 finite points, all identical, all on a line).
    Classification classify(std::span<const Eigen::Vector3f> points) const;
    /// describe_batch + classify_batch: per-cloud errors, never throws for bad clouds.
    std::vector<CloudClassification> classify_batch(std::span<const Points> clouds) const;

    /// Classifies every cluster of a segmented scene (described in parallel, classified as a
    /// batch); a cluster that cannot be described gets its error, the others their class.
    SceneRecognition recognize(SegmentationResult segmentation) const;
    /// The same for a segmentation of `frame`: verification (when on) checks each hypothesis
    /// against the frame's free space when the frame has the verification camera's size.
    SceneRecognition recognize(SegmentationResult segmentation, const PointCloud& frame) const;
    /// The same with each object's earlier fit (`priors`: one per cluster, in the segmentation's
    /// order, or empty), as verify() takes it. Throws std::invalid_argument when `priors` is
    /// neither empty nor one per cluster.
    SceneRecognition recognize(SegmentationResult segmentation, const PointCloud& frame,
                               std::span<const std::optional<PriorFit>> priors) const;
    /// segment_scene() + recognize(). Throws what segment_scene() throws (an empty cloud or one
    /// without finite points, bad options); a scene without plane or objects is no error.
    SceneRecognition recognize_scene(const PointCloud& scene,
                                     const SegmentationOptions& options = {}) const;

    /// When verifies(): fits the first options.verification.candidates neighbours of
    /// distinct models (of the named class unless verification.decide_class) to `observation`
    /// and makes the best fit the classification's model, view and refined pose (fit, verified;
    /// neighbours reordered best fit first; with decide_class also its class, the confidence
    /// its share of the neighbours). Otherwise leaves `c` as it is. Throws esf::IoError naming a
    /// mesh that cannot be loaded or a stored surface that is corrupt, std::invalid_argument for an
    /// observation fit_model refuses.
    ///
    /// With a `prior` whose model is among the neighbours, that model is fitted first from the
    /// prior's pose; verified with a score no more than verification.prior_tolerance below the
    /// prior's, it is the result and no other candidate is fitted (a track's object keeps its
    /// model while it fits: a third of the time); otherwise it joins the candidates.
    ///
    /// With `candidates`, every candidate fitted is appended to it, each fit complete (none is
    /// dropped early), for studies of the choice (bench/choice_study).
    void verify(Classification& c, const Observation& observation, const PriorFit* prior = nullptr,
                std::vector<CandidateFit>* candidates = nullptr) const;
    /// Verification is on and has the models' surfaces (stored or from verification_meshes).
    bool verifies() const;
    /// The surface samples of the model `c` names, placed where its fit put them (camera frame,
    /// Classification::pose), those that face the camera: what a picture draws as the fitted
    /// model. Empty when `c` has no fit or names a model the database does not hold. Throws
    /// what verify() throws for a surface that cannot be loaded.
    Points posed_surface(const Classification& c) const;

    const RecognizerInfo& info() const;
    const RecognizerOptions& options() const;
    /// The index and one label per view (class = category, model, view index, model -> camera
    /// pose), in the database's (category, model, view) order.
    const Classifier& classifier() const;

  private:
    SceneRecognition recognize_unverified(SegmentationResult segmentation) const;
    void verify_objects(SceneRecognition& scene, const PointCloud* frame,
                        std::span<const std::optional<PriorFit>> priors) const;
    void merge_parts(SceneRecognition& scene, const PointCloud& frame) const;  // merge_parts
    /// verify() against an observation prepared once (its grid and seen space built).
    void verify_prepared(Classification& c, const PreparedObservation& prepared,
                         const PriorFit* prior = nullptr,
                         std::vector<CandidateFit>* candidates = nullptr) const;
    /// merge_parts: `part`'s verified model fitted to the union from the part's pose; when it
    /// is verified and scores more than `merged`'s fit (or `merged` has none verified) and more
    /// than `bar`, `merged` becomes the part's classification with that pose and fit.
    void adopt_part_model(Classification& merged, const Classification& part,
                          const PreparedObservation& observation, double bar) const;

    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace esf
