#pragma once
// Objects followed over the frames of a sensor looking at a table: each object of a frame is
// given to the track standing at the same place on the table, and each track fuses the class
// evidence of the frames it was seen in.
//
// Position. An object's position is its centroid dropped onto the table plane along the plane's
// normal (camera frame, metres), so that a partial view's height does not move it. An object
// belongs to a track when its position lies within `match_distance` (default 5 cm) of the
// track's last position: about half the width of a cup, less than the distance between the
// centres of two objects that stand side by side, and more than the centroid of one object moves
// from frame to frame under noise and a slowly moving camera (below 1 cm). Pairs are made
// nearest first (ties: lower track id, then lower object index), each track and each object at
// most once; an object without a track starts one (ids 1, 2, ... in the order objects come), a
// track missed more than `max_misses` frames in a row ends. A track's position is its last
// object's, so that a slowly moving camera is followed.
//
// Fusion (FusionRule::kFrameVotes, the default). Each frame in which the object has a class
// votes for it: its own class, the one verification named (the best fit of its nearest
// models). The fused class has the most votes (ties: the larger summed earnings of its best
// model under kNearestModels, below, then more frames in which one of its models was the
// nearest, then the name first in order); its score is its votes, its confidence their share.
// Since verification names each frame's class, a frame's class is right more often than the
// nearest models' sums (BENCHMARKS.md, "Fusing the frames' verified classes"): on generated
// sequences of held-out model groups the vote names 1.5 / 0.1 points more objects right than
// single frames (the fold it was chosen on / another), where kNearestModels named 1.4 / 1.5
// fewer.
//
// Fusion (FusionRule::kNearestModels, the default before). A frame's classification lists its k
// nearest models, each at the distance of its nearest view, d_1 <= ... <= d_k
// (model_evidence()). Each of these models earns
//   w (1 - d / d_k),   w = 1 - d_1 / d_o,
// where d_o is the distance of the nearest model of another class than the nearest one's (d_k
// when all k share its class) (model_scores()). A model earns the more the nearer it is than the
// k-th (which earns 0; d_k is also a lower bound of every farther model's distance), and a frame
// counts the more the further its best class stands out (a frame torn between two classes adds
// little). Summed over the frames this is the k-NN of the whole track against each database
// model: every model's distance, truncated at the k-th and relative to it, summed over the
// views of the one unseen object, so that a model near in most views can beat one that is
// very near in a few. The track's classes are scored by their best model's sum; the fused class is
// the one with the largest score (ties: more frames in which one of its models was the nearest,
// then the name first in order), its confidence its share of the scores of the classes the
// track has seen (of the nearest-model frames while every score is 0). A frame whose models all
// lie at one distance (k = 1) gives its nearest model 1 and the others 0.
//
// On generated sequences of model groups the database does not hold (BENCHMARKS.md, "esf live:
// fusing frames over time"; k-NN frames, before verification named them) this named 0.5 to 2.4
// points more objects right than single frames;
// it is up to 4 points ahead of kClassLikelihood on the fold it was chosen on and level with it
// on another. That is far from the 10 points sought: most errors on unseen groups are the same
// in every view (a spray bottle is a bottle from every side), and no sum over views undoes them.
//
// Fusion (FusionRule::kClassLikelihood, the former rule). Each frame's classification gives
// every class c a probability
//   p(c) = 1/2 [c is the nearest neighbour's class] + 1/2 (votes of c among the k neighbours)/k,
// floored at `evidence_floor`, and the track sums log p(c) over the frames it was seen in (the
// frames taken as independent views: a naive Bayes product). The fused class is the one with
// the largest sum (ties: the name first in order); its confidence is its share of exp(sum)
// among the classes the track has seen. It makes a consistent error surer rather than right:
// on the fold kNearestModels was chosen on it named up to 3.4 points fewer objects right than
// single frames.
//
// Under every rule a frame in which the object has no class (too few points) counts as seen
// but adds no evidence.
//
// Deterministic: the same observations give the same tracks, ids and numbers.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "esf/core/enum_names.hpp"
#include "esf/recognition/classifier.hpp"
#include "esf/recognition/recognizer.hpp"

namespace esf {

/// How a track fuses the evidence of its frames (see the top of the file).
enum class FusionRule {
    kNearestModels,    ///< summed earnings of each frame's nearest models
    kClassLikelihood,  ///< summed class log-likelihoods (the first rule)
    kFrameVotes,       ///< a vote of the frames' own (verified) classes (the default)
};

/// "models", "likelihood" (to_string, parse_enum<FusionRule>).
template <>
struct EnumNames<FusionRule> {
    static constexpr const char* what = "fusion rule";
    static constexpr std::array<EnumName<FusionRule>, 3> table{
        {{FusionRule::kNearestModels, "models"},
         {FusionRule::kClassLikelihood, "likelihood"},
         {FusionRule::kFrameVotes, "frames"}}};
};

struct TrackingOptions {
    double match_distance = 0.05;  ///< metres on the table plane (> 0)
    int max_misses = 5;            ///< frames in a row a track survives unseen (>= 0)
    FusionRule fusion = FusionRule::kFrameVotes;
    /// track_frame(): verification starts from each track's last verified fit (PriorFit), which
    /// a track's object keeps while it fits (a third of the time per object); false: every
    /// frame is verified afresh.
    bool prior_fits = true;
    /// kClassLikelihood: smallest per-frame class probability, in (0, 1) (checked either way).
    double evidence_floor = 0.01;
};

/// Throws std::invalid_argument naming the option that is out of range.
void validate(const TrackingOptions& options);

/// One class's probability in one frame.
struct ClassEvidence {
    std::string class_name;
    double probability = 0.0;
};

/// The per-frame class probabilities of a classification (the top of the file), largest first
/// (ties by name); empty for a classification without neighbours.
std::vector<ClassEvidence> class_evidence(const Classification& c);

/// One of a frame's nearest models.
struct ModelEvidence {
    std::string class_name;
    std::string model_name;
    double distance = 0.0;  ///< of its nearest view among the neighbours
};

/// The distinct models of a classification's neighbours, each at its nearest view's distance,
/// nearest first (ties: in the neighbours' order); empty for a classification without
/// neighbours. A model is its (class, model name) pair.
std::vector<ModelEvidence> model_evidence(const Classification& c);

/// What one model earns in one frame.
struct ModelScore {
    std::string class_name;
    std::string model_name;
    double score = 0.0;  ///< in [0, 1]
};

/// One frame's earnings (the top of the file), in the order of `models`; empty for no models.
/// Throws std::invalid_argument for a distance that is negative or not finite, or models not
/// nearest first.
std::vector<ModelScore> model_scores(std::span<const ModelEvidence> models);

/// A frame's verified fit: the model verification aligned to the object, where and how well.
/// Fusion does not count it (adding each frame's fit score to its model's earnings named fewer
/// objects right on generated sequences: BENCHMARKS.md); the track keeps the last one as the
/// start of the next frame's verification (track_frame()).
struct FitEvidence {
    std::string class_name;
    std::string model_name;
    double score = 0.0;                                  ///< FitScore::score(), floored at 0
    int model_id = -1;                                   ///< Classification::best_model_id
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();  ///< model -> camera
};

/// One object of a frame, as the tracker sees it. The rule in use reads its own evidence; when
/// that is empty the object is seen, but without a class.
struct TrackedObservation {
    Eigen::Vector3f position = Eigen::Vector3f::Zero();  ///< on the table plane, metres
    std::vector<ClassEvidence> evidence;                 ///< kClassLikelihood's
    std::vector<ModelEvidence> models;                   ///< kNearestModels' (kFrameVotes' ties)
    std::string class_name;          ///< kFrameVotes': the frame's own class (empty: none)
    std::optional<FitEvidence> fit;  ///< when the object was verified
};

/// The observations of a recognised scene, in its objects' order.
std::vector<TrackedObservation> scene_observations(const SceneRecognition& scene);

/// A class's fused evidence in a track.
struct FusedClass {
    std::string class_name;
    /// kFrameVotes: the frames that named it; kNearestModels: its best model's earnings summed
    /// over the track's frames; kClassLikelihood: its log-likelihood summed over them.
    double score = 0.0;
    /// kFrameVotes, kNearestModels: its share of the classes' scores; kClassLikelihood: its
    /// share of exp(score) among the track's classes.
    double confidence = 0.0;
    std::string model;        ///< its best model (empty for kClassLikelihood)
    std::size_t nearest = 0;  ///< frames in which one of its models was nearest (not likelihood)
};

struct ObjectTrack {
    std::uint64_t id = 0;
    Eigen::Vector3f position = Eigen::Vector3f::Zero();  ///< the last object's
    std::size_t frames = 0;                              ///< frames it was seen in
    std::size_t evidence_frames = 0;                     ///< of them, frames with class evidence
    std::size_t misses = 0;       ///< frames in a row it has not been seen (0: seen now)
    std::size_t first_frame = 0;  ///< tracker frame numbers (0 = the first update)
    std::size_t last_frame = 0;
    /// The classes it has seen, most likely first; empty when it never had evidence.
    std::vector<FusedClass> classes;
    /// Its last verified fit (of the last frame that had one).
    std::optional<FitEvidence> fit;

    bool has_class() const { return !classes.empty(); }
    const std::string& class_name() const;  ///< classes[0] (empty string when none)
    double confidence() const;              ///< classes[0] (0 when none)
};

/// What one frame did.
struct TrackUpdate {
    std::size_t frame = 0;                    ///< this frame's number
    std::vector<std::uint64_t> object_track;  ///< per observation: the track it went to
    std::vector<std::uint64_t> born;          ///< ids of the tracks started now
    std::vector<ObjectTrack> ended;           ///< tracks that ended now (their last state)
};

class ObjectTracker {
  public:
    /// Throws std::invalid_argument for options validate() refuses.
    explicit ObjectTracker(const TrackingOptions& options = {});

    /// Adds one frame's objects. Throws std::invalid_argument for a non-finite position, or
    /// (kNearestModels) models model_scores() refuses.
    TrackUpdate update(std::span<const TrackedObservation> observations);
    /// scene_observations(scene), then update().
    TrackUpdate update(const SceneRecognition& scene);
    /// Per position (on the table plane, as TrackedObservation::position), the index in
    /// tracks() of the track update() would give it, or tracks().size() for a new track.
    std::vector<std::size_t> match(std::span<const Eigen::Vector3f> positions) const;

    /// The live tracks, by id.
    const std::vector<ObjectTrack>& tracks() const { return tracks_; }
    std::size_t frames() const { return frames_; }  ///< updates so far
    std::uint64_t tracks_started() const { return next_id_ - 1; }
    const TrackingOptions& options() const { return options_; }

  private:
    /// kNearestModels: one model's earnings in a track.
    struct ModelTally {
        std::string class_name;
        std::string model_name;
        double score = 0.0;
        std::size_t nearest = 0;  ///< frames in which it was the nearest model
    };
    /// What a track has summed.
    struct Sums {
        /// kClassLikelihood: per seen class, the sum of log(max(p, floor)) - log(floor).
        std::vector<std::pair<std::string, double>> excess;
        std::vector<ModelTally> models;                          ///< kNearestModels, kFrameVotes
        std::vector<std::pair<std::string, std::size_t>> votes;  ///< kFrameVotes: per class
    };

    TrackingOptions options_;
    std::vector<ObjectTrack> tracks_;
    std::vector<Sums> sums_;  ///< per track, same order
    std::size_t frames_ = 0;
    std::uint64_t next_id_ = 1;
};

/// One frame of a stream, recognised and tracked.
struct TrackedFrame {
    SceneRecognition scene;
    TrackUpdate update;
};

/// segment_scene(frame, segmentation), recognition against the frame (Recognizer::recognize)
/// with each object's track's last fit as its prior (TrackingOptions::prior_fits), then
/// tracker.update(). What esf live does with each frame. Throws what those throw.
TrackedFrame track_frame(const Recognizer& recognizer, ObjectTracker& tracker,
                         const PointCloud& frame, const SegmentationOptions& segmentation);

}  // namespace esf
