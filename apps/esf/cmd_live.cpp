// esf live DB : recognise and track the objects on a table, frame by frame, from a Kinect (or a
// recording).

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "cli_common.hpp"
#include "cli_recognize.hpp"
#include "cli_scene.hpp"
#include "commands.hpp"
#include "core/elapsed_time.hpp"
#include "esf/io/kinect_raw.hpp"
#include "esf/recognition/object_tracks.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/report/scene_page.hpp"
#include "esf/segmentation/segmentation.hpp"
#include "live_source.hpp"

namespace esf::cli {

namespace {

struct LiveArgs {
    RecognizerArgs recognizer;
    SceneInputArgs input;
    int device = 0;
    std::size_t frames = 0;
    double seconds = 0.0;
    double timeout = 5.0;
    std::string report;
    std::string recording;
    TrackingOptions tracking;
};

using Clock = std::chrono::steady_clock;

volatile std::sig_atomic_t interrupted = 0;

void on_interrupt(int) { interrupted = 1; }

/// SIGINT and SIGTERM set `interrupted` while it lives; the previous handlers come back after.
class InterruptGuard {
  public:
    InterruptGuard() {
        interrupted = 0;
        struct sigaction action {};
        action.sa_handler = on_interrupt;
        sigemptyset(&action.sa_mask);
        sigaction(SIGINT, &action, &old_int_);
        sigaction(SIGTERM, &action, &old_term_);
    }
    ~InterruptGuard() {
        sigaction(SIGINT, &old_int_, nullptr);
        sigaction(SIGTERM, &old_term_, nullptr);
    }
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;

  private:
    struct sigaction old_int_ {};
    struct sigaction old_term_ {};
};

/// The JSON lines go to the real stdout while file descriptor 1 points at stderr: libfreenect
/// (fakenect) prints its messages on stdout, which must carry JSON only.
class JsonOutput {
  public:
    explicit JsonOutput(bool divert) {
        if (!divert) {
            out_ = stdout;
            return;
        }
        std::fflush(stdout);
        const int saved = dup(STDOUT_FILENO);
        if (saved < 0 || dup2(STDERR_FILENO, STDOUT_FILENO) < 0)
            throw std::runtime_error("cannot set stdout aside for the JSON lines");
        out_ = fdopen(saved, "w");
        if (!out_) throw std::runtime_error("cannot set stdout aside for the JSON lines");
        saved_ = saved;
    }
    ~JsonOutput() {
        if (saved_ < 0) return;
        std::fflush(stdout);  // the driver's text, to stderr
        std::fflush(out_);
        dup2(saved_, STDOUT_FILENO);
        std::fclose(out_);
    }
    JsonOutput(const JsonOutput&) = delete;
    JsonOutput& operator=(const JsonOutput&) = delete;
    std::FILE* file() const { return out_; }

  private:
    std::FILE* out_ = nullptr;
    int saved_ = -1;
};

double rounded(double x, double scale = 1e4) { return std::round(x * scale) / scale; }

nlohmann::json position_json(const Eigen::Vector3f& v) {
    return {rounded(v.x()), rounded(v.y()), rounded(v.z())};
}

nlohmann::json frame_json(std::size_t frame, double time, std::size_t skipped,
                          const SceneRecognition& scene, const TrackUpdate& update,
                          const ObjectTracker& tracker) {
    nlohmann::json out;
    out["frame"] = frame;
    out["time"] = rounded(time);
    out["skipped"] = skipped;
    out["message"] = scene.message;
    out["objects"] = nlohmann::json::array();
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const RecognizedObject& o = scene.objects[i];
        nlohmann::json entry;
        if (o.classified()) {
            const Classification& c = o.classification;
            entry["class"] = c.class_name;
            entry["confidence"] = rounded(c.confidence);
            if (c.fit) {  // verified: the model aligned to the points, and how well
                entry["model"] = c.best_model;
                entry["pose"] = pose_json(c.pose);
                entry["fit"] = {{"inliers", rounded(c.fit->inliers)},
                                {"support", rounded(c.fit->support)},
                                {"violations", rounded(c.fit->violations)},
                                {"rms_mm", rounded(c.fit->rms_mm, 100)}};
                entry["verified"] = c.verified;
            }
        } else {
            entry["class"] = nullptr;
            entry["confidence"] = 0.0;
        }
        entry["track"] = update.object_track[i];
        entry["centroid"] = position_json(o.cluster.centroid);
        entry["size"] = position_json(o.cluster.size);
        entry["points"] = o.cluster.points.size();
        out["objects"].push_back(std::move(entry));
    }
    out["tracks"] = nlohmann::json::array();
    for (const ObjectTrack& t : tracker.tracks()) {
        nlohmann::json entry;
        entry["id"] = t.id;
        if (t.has_class())
            entry["class"] = t.class_name();
        else
            entry["class"] = nullptr;
        // The fused class's best model (fusion "frames" and "models"; null for "likelihood").
        if (t.has_class() && !t.classes.front().model.empty())
            entry["model"] = t.classes.front().model;
        else
            entry["model"] = nullptr;
        entry["confidence"] = rounded(t.confidence());
        entry["frames"] = t.frames;
        entry["misses"] = t.misses;
        entry["position"] = position_json(t.position);
        if (t.fit)  // its last verified fit
            entry["fit"] = {{"class", t.fit->class_name},
                            {"model", t.fit->model_name},
                            {"pose", pose_json(t.fit->pose)},
                            {"score", rounded(t.fit->score)}};
        out["tracks"].push_back(std::move(entry));
    }
    return out;
}

/// The page of the latest frame, reloading itself every second.
void write_live_page(const std::string& dir, const std::string& source, std::size_t frame,
                     const PointCloud& cloud, const SceneRecognition& scene, float plane_distance) {
    ScenePageOptions options;
    options.title = "esf live";
    options.plane_distance = plane_distance;
    std::string html =
        scene_page_html(source + ", frame " + std::to_string(frame), cloud, scene, {}, options);
    const std::string refresh = "<meta http-equiv=\"refresh\" content=\"1\">";
    const std::size_t head = html.find("<head>");
    if (head != std::string::npos) html.insert(head + 6, refresh);
    write_page(dir, "index.html", html);
}

void run_live(LiveArgs& args) {
    if (args.seconds < 0.0 || !std::isfinite(args.seconds))
        throw CLI::ValidationError("--seconds", "--seconds must be 0 (no limit) or positive");
    SegmentationOptions segmentation = segmentation_options(args.input);
    segmentation.threads = args.recognizer.options.threads;
    validate(args.tracking);
    const Recognizer recognizer(args.recognizer.database, recognizer_options(args.recognizer));
    if (!args.recognizer.no_weights)
        warn_if_weights_stale(args.recognizer.database, recognizer.info().setup.kind.name);
    warn_if_unverified(recognizer);

    const bool device = args.recording.empty();
    if (device && !kinect_supported()) open_kinect_source(args.device);  // throws how to get it
    JsonOutput output(device);
    std::unique_ptr<FrameSource> source =
        device ? open_kinect_source(args.device) : open_recording_source(args.recording);
    const std::string source_name = source->name();
    const InterruptGuard interrupt_guard;
    ObjectTracker tracker(args.tracking);
    const bool status_line = stderr_is_terminal();

    const auto start = Clock::now();
    using detail::seconds_since;
    Clock::time_point last_arrival = start;
    double last_status = -1.0, last_page = -1.0;
    std::optional<double> first_time;
    std::size_t processed = 0;
    std::string reason, error;
    int exit_code = 0;
    KinectFrame frame;
    while (true) {
        if (interrupted) {
            reason = "interrupted";
            exit_code = 130;
            break;
        }
        if (args.seconds > 0.0 && seconds_since(start) >= args.seconds) {
            reason = "--seconds reached";
            break;
        }
        const FrameWait wait = source->next(frame, std::chrono::milliseconds(100));
        if (wait == FrameWait::kEnded) {
            reason = "the recording ended";
            break;
        }
        if (wait == FrameWait::kFailed) {
            error = source->message();
            break;
        }
        if (wait == FrameWait::kTimeout) {
            if (seconds_since(last_arrival) > args.timeout) {
                char text[160];
                std::snprintf(text, sizeof text, "no frame from %s for %.1f s (device lost?)",
                              source_name.c_str(), args.timeout);
                error = text;
                break;
            }
            continue;
        }
        last_arrival = Clock::now();
        if (!first_time) first_time = frame.time;
        const PointCloud cloud = kinect_raw_to_cloud(frame.depth, frame.rgb);
        const TrackedFrame tracked = track_frame(recognizer, tracker, cloud, segmentation);
        const SceneRecognition& scene = tracked.scene;
        const TrackUpdate& update = tracked.update;
        const std::size_t skipped = source->skipped();
        const std::string line =
            frame_json(processed, frame.time - *first_time, skipped, scene, update, tracker).dump();
        std::fprintf(output.file(), "%s\n", line.c_str());
        std::fflush(output.file());
        ++processed;
        const double elapsed = seconds_since(start);
        if (status_line && elapsed - last_status >= 0.1) {
            last_status = elapsed;
            std::fprintf(stderr,
                         "\r\033[Kframe %zu  %.1f frames/s  skipped %zu  objects %zu  tracks %zu",
                         processed, static_cast<double>(processed) / std::max(elapsed, 1e-9),
                         skipped, scene.objects.size(), tracker.tracks().size());
        }
        if (!args.report.empty() && elapsed - last_page >= 1.0) {
            last_page = elapsed;
            write_live_page(args.report, source_name, processed - 1, cloud, scene,
                            segmentation.plane_distance);
        }
        if (args.frames > 0 && processed >= args.frames) {
            reason = "--frames reached";
            break;
        }
    }
    const bool stopped = source->stop();
    std::fflush(stdout);  // the driver's messages (on stderr while it runs) before the summary
    if (status_line) std::fprintf(stderr, "\r\033[K");
    const double elapsed = seconds_since(start);
    std::fprintf(stderr,
                 "esf live: %zu frames processed, %zu skipped, %llu tracks (%zu live), %.1f "
                 "frames/s, %s%s\n",
                 processed, source->skipped(),
                 static_cast<unsigned long long>(tracker.tracks_started()), tracker.tracks().size(),
                 static_cast<double>(processed) / std::max(elapsed, 1e-9), source_name.c_str(),
                 error.empty() ? (": " + reason).c_str() : "");
    if (!stopped) std::fprintf(stderr, "esf live: the driver did not stop; leaving it\n");
    if (std::ferror(output.file())) throw std::runtime_error("writing the output failed");
    if (!error.empty()) throw std::runtime_error(error);
    if (exit_code != 0) throw ExitStatus{exit_code};
}

}  // namespace

void add_live_command(CLI::App& app) {
    auto args = std::make_shared<LiveArgs>();
    CLI::App* cmd = add_command(
        app, "live", "Recognise and track objects live from a Kinect v1 or a recording",
        "Recognise and track the objects on a table from a Kinect v1 (libfreenect, 11-bit raw "
        "depth and RGB, 640 x 480), or from a recording (--recording DIR, or fakenect DIR esf "
        "live DB). Each frame is segmented and its objects classified as by esf scene; an "
        "object is the same across frames when it stands within --match-distance of where a "
        "track last saw it, and each track fuses its frames (--fusion frames: a vote of the "
        "classes its frames named, each verified by the best fit of its nearest models; models: "
        "each frame's k nearest models earn by how much nearer than the k-th they are, weighed "
        "by how far the best class stands out, and the track names the class of the model that "
        "earned most; likelihood: summed class log-likelihoods). Prints one "
        "JSON line per processed frame on stdout: {frame, time, skipped, message, objects: "
        "[{class, confidence, track, centroid, size, points, and when verified model, pose, "
        "fit, verified}], tracks: [{id, class, model, confidence, frames, misses, position, and "
        "fit: {class, model, pose, score}, its last verified fit}]} (metres, camera frame; poses "
        "16 numbers, model -> camera, row-major; a track's position is on the table plane). A "
        "track's last verified model is fitted first from where it stood and kept while it "
        "fits (--no-prior-fits: every frame verified afresh, a third slower). A status line "
        "on stderr when it is a terminal, and a summary "
        "line at the end. Frames that arrive while one is processed replace it and are "
        "counted as skipped. Ends at --frames, --seconds, the end of a recording or Ctrl-C "
        "(exit 130); no frame for --timeout seconds or a lost device is an error (exit 2).");
    add_recognizer_options(*cmd, args->recognizer);
    cmd->add_option("--device", args->device, "Kinect number (libfreenect's order)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("--frames", args->frames, "Stop after this many processed frames, 0 = no limit")
        ->capture_default_str();
    cmd->add_option("--seconds", args->seconds, "Stop after this many seconds, 0 = no limit")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("--timeout", args->timeout,
                    "Seconds without a frame after which the device counts as lost")
        ->check(CLI::Range(0.1, 600.0))
        ->capture_default_str();
    cmd->add_option("--recording", args->recording,
                    "Read a recording folder (fakenect-record's format, esf record-scenes) "
                    "directly, as fast as frames are processed, instead of a Kinect")
        ->check(CLI::ExistingDirectory);
    cmd->add_option("--report", args->report,
                    "Keep DIR/index.html: the latest frame's page (rewritten every second, it "
                    "reloads itself)");
    cmd->add_option("--match-distance", args->tracking.match_distance,
                    "Metres on the table within which an object is the same as a track's")
        ->check(CLI::Range(0.001, 1.0))
        ->capture_default_str();
    cmd->add_option("--max-misses", args->tracking.max_misses,
                    "Frames in a row a track survives unseen")
        ->check(CLI::Range(0, 1000))
        ->capture_default_str();
    cmd->add_flag_callback(
        "--no-prior-fits", [args] { args->tracking.prior_fits = false; },
        "Verify every frame afresh instead of first fitting each track's last verified model "
        "from where it stood");
    add_enum_option(*cmd, "--fusion", args->tracking.fusion,
                    "How a track fuses its frames: frames (a vote of the classes its frames "
                    "named), models (the nearest models' earnings summed over the frames) or "
                    "likelihood (summed class log-likelihoods)");
    add_segmentation_options(*cmd, args->input);
    cmd->callback([args] { run_live(*args); });
}

}  // namespace esf::cli
