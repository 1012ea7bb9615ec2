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
// Fusion. Each frame's classification gives every class c a probability
//   p(c) = 1/2 [c is the nearest neighbour's class] + 1/2 (votes of c among the k neighbours)/k,
// floored at `evidence_floor`, and the track sums log p(c) over the frames it was seen in (the
// frames taken as independent views: a naive Bayes product). The fused class is the one with
// the largest sum (ties: the name first in order); its confidence is its share of exp(sum)
// among the classes the track has seen. A frame in which the object has no class (too few
// points) counts as seen but adds no evidence.
//
// Deterministic: the same observations give the same tracks, ids and numbers.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "esf/recognition/classifier.hpp"
#include "esf/recognition/recognizer.hpp"

namespace esf {

struct TrackingOptions {
    double match_distance = 0.05;  ///< metres on the table plane (> 0)
    int max_misses = 5;            ///< frames in a row a track survives unseen (>= 0)
    double evidence_floor = 0.01;  ///< smallest per-frame class probability, in (0, 1)
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

/// One object of a frame, as the tracker sees it.
struct TrackedObservation {
    Eigen::Vector3f position = Eigen::Vector3f::Zero();  ///< on the table plane, metres
    std::vector<ClassEvidence> evidence;                 ///< empty: seen, but without a class
};

/// The observations of a recognised scene, in its objects' order.
std::vector<TrackedObservation> scene_observations(const SceneRecognition& scene);

/// A class's fused evidence in a track.
struct FusedClass {
    std::string class_name;
    double log_likelihood = 0.0;  ///< sum over the track's frames with evidence
    double confidence = 0.0;      ///< share of exp(log_likelihood) among the track's classes
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

    /// Adds one frame's objects. Throws std::invalid_argument for a non-finite position.
    TrackUpdate update(std::span<const TrackedObservation> observations);
    /// scene_observations(scene), then update().
    TrackUpdate update(const SceneRecognition& scene);

    /// The live tracks, by id.
    const std::vector<ObjectTrack>& tracks() const { return tracks_; }
    std::size_t frames() const { return frames_; }  ///< updates so far
    std::uint64_t tracks_started() const { return next_id_ - 1; }
    const TrackingOptions& options() const { return options_; }

  private:
    TrackingOptions options_;
    std::vector<ObjectTrack> tracks_;
    /// Per track (same order): per seen class, the sum of log(max(p, floor)) - log(floor).
    std::vector<std::vector<std::pair<std::string, double>>> excess_;
    std::size_t frames_ = 0;
    std::uint64_t next_id_ = 1;
};

}  // namespace esf
