#pragma once
// Generated scene sequences: a camera moving over a generated table (clutter_scene.hpp), each
// sequence written as a Kinect recording that fakenect plays back (io/kinect_recording.hpp), and
// the measure of what fusing frames over time gains (recognition/object_tracks.hpp).
//
//   DIR/sequence_NNN/        a recording: INDEX.txt, d-*.pgm (raw 11-bit depth), r-*.ppm (grey)
//   DIR/sequences.json       {"seed", "root", "frames", "frame_rate", "sweep", "sequences":
//                            [{"folder", "type", "objects": [{"object_id", "class", "model"}],
//                            "frames": [{"camera" (world -> camera, 16 numbers row-major),
//                            "objects": [{"object_id", "pixels", "centroid" (camera frame, of
//                            its pixels; null below kClutterMinLabelledPixels)}]}]}]}
//
// Sequence i holds the objects of ClutterComposer scene i (no wall, no table edge) on a table
// plane; its camera starts where the scene's camera is, turned about the vertical axis through
// the point it looks at by -sweep/2, and turns by `sweep` degrees over the sequence at the same
// height and distance. Each frame has its own sensor noise. The same options give the same
// bytes at any thread count.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "esf/recognition/object_tracks.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/render/clutter_scene.hpp"
#include "esf/segmentation/segmentation.hpp"
#include "esf/training/training.hpp"

namespace esf {

struct SceneSequenceOptions {
    std::size_t sequences = 10;
    std::size_t frames = 30;   ///< per sequence
    double sweep = 30.0;       ///< degrees the camera turns about the table's vertical
    double frame_rate = 30.0;  ///< frames a second of the recording's clock
    ClutterOptions clutter;    ///< seed, sensor, types (walls and table edges are left out)
    GroupSelection groups;     ///< the models sequences are made of
    std::string catalog;       ///< as TrainingOptions::catalog
    bool use_catalog = true;
    int threads = 0;  ///< 0 = all cores
    /// Called after each sequence written with (done, in all); calls are serialised.
    std::function<void(std::size_t, std::size_t)> progress;
};

struct SceneSequenceSet {
    std::vector<std::string> folders;  ///< one recording per sequence, in order
    std::string truth;                 ///< sequences.json
    std::size_t models = 0;
    std::size_t objects = 0;  ///< placed in all sequences
};

/// Loads the models of `root` (plan_models), composes and renders the sequences and writes them
/// to `output` (created when missing). Throws std::invalid_argument for bad options or a
/// selection without models, esf::IoError for files that cannot be read or written.
SceneSequenceSet generate_scene_sequences(const std::string& root, const std::string& output,
                                          const SceneSequenceOptions& options);

/// One true object of one frame as evaluate_scene_sequences() scores it (for studies of fusion
/// rules: SequenceFusionOptions::on_object).
struct SequenceFrameObject {
    std::size_t sequence = 0;  ///< in sequences.json's order
    std::size_t frame = 0;     ///< within the sequence
    std::uint32_t object_id = 0;
    std::string true_class;
    const RecognizedObject* found = nullptr;  ///< the frame's object matched to it, or none
    std::uint64_t track = 0;                  ///< found's track id (0: none)
    std::string track_class;                  ///< that track's class after this frame
    const PointCloud* cloud = nullptr;        ///< the frame
};

struct SequenceFusionOptions {
    /// Frames after which the tracks' classes are scored (1 = a single frame).
    std::vector<std::size_t> checkpoints = {1, 10, 30};
    SegmentationOptions segmentation;
    TrackingOptions tracking;
    /// A true object is found in a frame when an object's centroid lies within this distance
    /// (metres) of the centroid of its pixels.
    double match_distance = 0.05;
    /// Called for each true object of each frame after it is scored, in order (empty: none).
    std::function<void(const SequenceFrameObject&)> on_object;
};

/// The score after a number of frames.
struct SequenceFusionPoint {
    std::size_t frames = 0;        ///< the checkpoint
    std::size_t objects = 0;       ///< true objects seen in that frame (all sequences)
    std::size_t found = 0;         ///< of them, matched by an object of the frame
    std::size_t single_right = 0;  ///< named right by that frame alone
    std::size_t fused_right = 0;   ///< named right by the object's track
    /// Named right by at least one of the object's frames so far: the most that any fusion
    /// rule choosing among the classes its frames named could reach.
    std::size_t any_right = 0;
    /// Of `objects`, those of a class the database has no model of: never named right, and
    /// counted in `objects` all the same.
    std::size_t unknown = 0;
};

struct SequenceFusionResult {
    std::vector<SequenceFusionPoint> points;  ///< per checkpoint (those within the sequences)
    std::size_t frame_objects = 0;            ///< true objects seen, summed over every frame
    std::size_t frame_single_right = 0;       ///< of them, named right by their frame alone
    std::size_t frame_fused_right = 0;        ///< of them, named right by their track then
    std::size_t frame_unknown = 0;            ///< of them, of a class the database has no model of
    std::size_t frame_any_right = 0;  ///< of them, named right by one of their frames so far
    /// True objects (of all sequences) seen in at least one frame, and of them those named right
    /// by at most a tenth and by at least nine tenths of the frames they were seen in: errors
    /// that are the same from every side leave fusion nothing to decide.
    std::size_t objects = 0;
    std::size_t objects_rarely_right = 0;
    std::size_t objects_mostly_right = 0;
    std::size_t frames = 0;  ///< frames processed
    double seconds = 0.0;    ///< frames' processing time (segment, recognise, track)
};

/// Plays each recording of a generate_scene_sequences() folder through segmentation,
/// recognition and tracking (options.tracking, its fusion rule included), and scores the
/// tracks' classes against sequences.json. Throws
/// esf::IoError naming a bad file.
SequenceFusionResult evaluate_scene_sequences(const Recognizer& recognizer,
                                              const std::string& folder,
                                              const SequenceFusionOptions& options = {});

}  // namespace esf
