// Generated scene sequences as Kinect recordings, and the fusion score on them
// (esf/evaluation/scene_sequences.hpp).

#include "esf/evaluation/scene_sequences.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

#include "core/atomic_file.hpp"
#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "esf/io/kinect_raw.hpp"
#include "esf/io/kinect_recording.hpp"
#include "esf/render/render.hpp"
#include "esf/render/view_sphere.hpp"
#include "evaluation/matrix_json.hpp"
#include "evaluation/scene_generation.hpp"

namespace esf {

namespace fs = std::filesystem;

namespace {

constexpr std::uint64_t kSequenceNoiseKey = 0x5e9e4ce5e9e4ce00ULL;

std::string sequence_folder_name(std::size_t index) {
    char name[32];
    std::snprintf(name, sizeof name, "sequence_%03zu", index);
    return name;
}

/// The point on the table (z = 0) the camera looks at: its optical axis met with the plane, or
/// the point below the camera when the axis misses it.
Eigen::Vector3d looked_at(const Eigen::Isometry3d& world_to_camera) {
    const Eigen::Isometry3d camera_to_world = world_to_camera.inverse();
    const Eigen::Vector3d eye = camera_to_world.translation();
    const Eigen::Vector3d forward = camera_to_world.linear().col(2);
    if (forward.z() < -1e-6) {
        const double t = -eye.z() / forward.z();
        return eye + t * forward;
    }
    return {eye.x(), eye.y(), 0.0};
}

struct RenderedSequence {
    nlohmann::json truth;
    std::size_t objects = 0;
};

RenderedSequence render_sequence(const ClutterComposer& composer, std::size_t index,
                                 const SceneSequenceOptions& options, const fs::path& folder) {
    const ClutterScene scene = composer.compose(index);
    const Eigen::Isometry3d camera_to_world = scene.world_to_camera.inverse();
    std::vector<SceneObject> objects;
    std::vector<Mesh> sized(scene.objects.size());  // objects not of their models' size
    RenderedSequence out;
    out.truth["folder"] = folder.filename().string();
    out.truth["type"] = to_string(scene.type);
    out.truth["objects"] = nlohmann::json::array();
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const ClutterObject& o = scene.objects[i];
        const ClutterModel& m = composer.models()[o.model];
        // pose: file coordinates -> camera with the scale and size; the mesh is in metres.
        Eigen::Matrix4d unscale = Eigen::Matrix4d::Identity();
        unscale.topLeftCorner<3, 3>() /= m.scale * o.size;
        Eigen::Isometry3d to_world;
        to_world.matrix() = camera_to_world.matrix() * o.pose * unscale;
        to_world.makeAffine();
        const Mesh* mesh = &m.mesh;
        if (o.size != 1.0) {
            sized[i] = scaled_mesh(m.mesh, o.size);
            mesh = &sized[i];
        }
        objects.push_back({mesh, to_world});
        out.truth["objects"].push_back(
            {{"object_id", o.object_id}, {"class", m.category}, {"model", m.file}});
    }
    out.objects = objects.size();

    const Eigen::Vector3d target = looked_at(scene.world_to_camera);
    const Eigen::Vector3d eye0 = camera_to_world.translation() - target;
    KinectRecordingWriter writer(folder.string());
    out.truth["frames"] = nlohmann::json::array();
    const std::size_t frames = options.frames;
    for (std::size_t f = 0; f < frames; ++f) {
        const double share =
            frames > 1 ? static_cast<double>(f) / static_cast<double>(frames - 1) - 0.5 : 0.0;
        const double angle = options.sweep * share * std::numbers::pi / 180.0;
        const Eigen::Vector3d eye =
            target + Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()) * eye0;
        const Eigen::Isometry3d world_to_camera = look_at(eye, target);
        SceneOptions render;
        render.camera = composer.options().camera;
        render.noise = composer.options().noise;
        render.seed = (composer.options().seed ^ kSequenceNoiseKey) + index * 100003 + f;
        render.table_plane = true;
        render.table_half_size = 0.75;
        render.max_depth = 4.5;
        render.threads = 1;
        const PointCloud cloud = render_scene(objects, world_to_camera, render);

        nlohmann::json frame;
        frame["camera"] = detail::row_major_json(world_to_camera.matrix());
        frame["objects"] = nlohmann::json::array();
        for (std::size_t i = 0; i < objects.size(); ++i) {
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            std::size_t pixels = 0;
            for (std::size_t p = 0; p < cloud.points.size(); ++p)
                if (cloud.labels[p] == kSceneLabelFirstObject + i && cloud.points[p].allFinite()) {
                    sum += cloud.points[p].cast<double>();
                    ++pixels;
                }
            nlohmann::json o = {{"object_id", scene.objects[i].object_id}, {"pixels", pixels}};
            if (pixels >= kClutterMinLabelledPixels) {
                const Eigen::Vector3d c = sum / static_cast<double>(pixels);
                o["centroid"] = {c.x(), c.y(), c.z()};
            } else {
                o["centroid"] = nullptr;
            }
            frame["objects"].push_back(std::move(o));
        }
        out.truth["frames"].push_back(std::move(frame));

        KinectFrame k;
        k.time = 1.0 + static_cast<double>(f) / options.frame_rate;
        k.timestamp = static_cast<std::uint32_t>(f * 2000000u);
        k.depth = kinect_cloud_to_raw(cloud, render.camera);
        k.rgb = kinect_cloud_to_rgb(cloud);
        writer.add(k);
    }
    writer.finish();
    return out;
}

nlohmann::json read_json(const std::string& path) {
    std::error_code error;
    if (!fs::is_regular_file(path, error))
        throw IoError(file_message(path, 0, "no such file (esf record-scenes writes it)"));
    std::ifstream in(path);
    try {
        return nlohmann::json::parse(in);
    } catch (const std::exception& e) {
        throw IoError(file_message(path, 0, std::string("not JSON: ") + e.what()));
    }
}

}  // namespace

SceneSequenceSet generate_scene_sequences(const std::string& root, const std::string& output,
                                          const SceneSequenceOptions& options) {
    if (options.sequences == 0 || options.sequences > 10000)
        throw std::invalid_argument("scene sequences: 1 to 10000 sequences, got " +
                                    std::to_string(options.sequences));
    if (options.frames == 0 || options.frames > 100000)
        throw std::invalid_argument("scene sequences: 1 to 100000 frames, got " +
                                    std::to_string(options.frames));
    if (!(std::isfinite(options.sweep) && std::abs(options.sweep) <= 360.0))
        throw std::invalid_argument("scene sequences: sweep must be within 360 degrees");
    if (!(std::isfinite(options.frame_rate) && options.frame_rate > 0.0 &&
          options.frame_rate <= 1000.0))
        throw std::invalid_argument("scene sequences: frame rate must be in (0, 1000]");
    if (options.clutter.camera.width != kKinectFrameWidth ||
        options.clutter.camera.height != kKinectFrameHeight)
        throw std::invalid_argument("scene sequences: a Kinect recording is 640 x 480");
    const int threads = resolve_threads(options.threads);
    ClutterOptions clutter = options.clutter;
    clutter.wall_share = 0.0;
    clutter.edge_share = 0.0;
    const ClutterComposer composer(
        detail::load_clutter_models(root, options.catalog, options.use_catalog, options.groups,
                                    threads),
        clutter);
    detail::create_output_folder(output);

    std::vector<RenderedSequence> rendered(options.sequences);
    std::mutex progress_mutex;
    std::size_t done = 0;
    parallel_for(options.sequences, threads, [&](std::size_t i) {
        rendered[i] =
            render_sequence(composer, i, options, fs::path(output) / sequence_folder_name(i));
        if (options.progress) {
            std::lock_guard lock(progress_mutex);
            options.progress(++done, options.sequences);
        }
    });

    SceneSequenceSet result;
    result.models = composer.models().size();
    nlohmann::json truth;
    truth["seed"] = clutter.seed;
    truth["root"] = root;
    truth["frames"] = options.frames;
    truth["frame_rate"] = options.frame_rate;
    truth["sweep"] = options.sweep;
    truth["sequences"] = nlohmann::json::array();
    for (std::size_t i = 0; i < rendered.size(); ++i) {
        result.folders.push_back((fs::path(output) / sequence_folder_name(i)).string());
        result.objects += rendered[i].objects;
        truth["sequences"].push_back(std::move(rendered[i].truth));
    }
    result.truth = (fs::path(output) / "sequences.json").string();
    const std::string text = truth.dump(1) + "\n";
    detail::write_file_atomically(result.truth, text.data(), text.size());
    return result;
}

SequenceFusionResult evaluate_scene_sequences(const Recognizer& recognizer,
                                              const std::string& folder,
                                              const SequenceFusionOptions& options) {
    const std::string truth_path = (fs::path(folder) / "sequences.json").string();
    const nlohmann::json truth = read_json(truth_path);
    SequenceFusionResult result;
    for (const std::size_t c : options.checkpoints) result.points.push_back({c, 0, 0, 0, 0, 0, 0});
    std::set<std::string> known;  // the classes of the database's views
    for (const ViewLabel& label : recognizer.classifier().labels()) known.insert(label.class_name);
    using Clock = std::chrono::steady_clock;
    try {
        std::size_t sequence_index = 0;
        for (const nlohmann::json& sequence : truth.at("sequences")) {
            const std::string name = sequence.at("folder").get<std::string>();
            if (name.find('/') != std::string::npos || name.empty() || name[0] == '.')
                throw IoError(file_message(truth_path, 0, "bad folder name '" + name + "'"));
            std::map<std::uint32_t, std::string> class_of;
            for (const nlohmann::json& o : sequence.at("objects"))
                class_of[o.at("object_id").get<std::uint32_t>()] = o.at("class").get<std::string>();
            // Per true object: frames seen, frames named right.
            std::map<std::uint32_t, std::pair<std::size_t, std::size_t>> seen;
            KinectRecordingReader reader((fs::path(folder) / name).string());
            ObjectTracker tracker(options.tracking);
            const nlohmann::json& frames = sequence.at("frames");
            for (std::size_t f = 0; f < frames.size(); ++f) {
                const std::optional<KinectFrame> frame = reader.next();
                if (!frame)
                    throw IoError(file_message(name, 0, "fewer frames than sequences.json lists"));
                const auto start = Clock::now();
                const PointCloud cloud = kinect_raw_to_cloud(frame->depth, frame->rgb);
                const TrackedFrame tracked =
                    track_frame(recognizer, tracker, cloud, options.segmentation);
                const SceneRecognition& scene = tracked.scene;
                const TrackUpdate& update = tracked.update;
                result.seconds += std::chrono::duration<double>(Clock::now() - start).count();
                ++result.frames;

                SequenceFusionPoint* point = nullptr;
                for (SequenceFusionPoint& p : result.points)
                    if (p.frames == f + 1) point = &p;
                for (const nlohmann::json& o : frames[f].at("objects")) {
                    if (o.at("centroid").is_null()) continue;
                    const Eigen::Vector3f c(o["centroid"][0].get<float>(),
                                            o["centroid"][1].get<float>(),
                                            o["centroid"][2].get<float>());
                    const auto object_id = o.at("object_id").get<std::uint32_t>();
                    const std::string& true_class = class_of.at(object_id);
                    // The nearest object of the frame within the match distance.
                    std::size_t best = scene.objects.size();
                    double best_distance = options.match_distance;
                    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
                        const double d =
                            static_cast<double>((scene.objects[i].cluster.centroid - c).norm());
                        if (d <= best_distance) {
                            best_distance = d;
                            best = i;
                        }
                    }
                    bool single = false, fused = false;
                    SequenceFrameObject record;
                    if (best < scene.objects.size()) {
                        const RecognizedObject& found = scene.objects[best];
                        single =
                            found.classified() && found.classification.class_name == true_class;
                        for (const ObjectTrack& t : tracker.tracks())
                            if (t.id == update.object_track[best]) {
                                fused = t.class_name() == true_class;
                                record.track = t.id;
                                record.track_class = t.class_name();
                            }
                        record.found = &found;
                    }
                    if (options.on_object) {
                        record.sequence = sequence_index;
                        record.frame = f;
                        record.object_id = object_id;
                        record.true_class = true_class;
                        record.cloud = &cloud;
                        options.on_object(record);
                    }
                    const bool unknown = !known.contains(true_class);
                    auto& [frames_seen, frames_right] = seen[object_id];
                    ++frames_seen;
                    frames_right += single;
                    const bool any = frames_right > 0;
                    ++result.frame_objects;
                    result.frame_any_right += any;
                    result.frame_single_right += single;
                    result.frame_fused_right += fused;
                    result.frame_unknown += unknown;
                    if (point) {
                        ++point->objects;
                        point->found += best < scene.objects.size();
                        point->single_right += single;
                        point->fused_right += fused;
                        point->any_right += any;
                        point->unknown += unknown;
                    }
                }
            }
            for (const auto& [id, counts] : seen) {
                ++result.objects;
                result.objects_rarely_right += 10 * counts.second <= counts.first;
                result.objects_mostly_right += 10 * counts.second >= 9 * counts.first;
            }
            ++sequence_index;
        }
    } catch (const nlohmann::json::exception& e) {
        throw IoError(file_message(truth_path, 0, e.what()));
    }
    std::erase_if(result.points, [](const SequenceFusionPoint& p) { return p.objects == 0; });
    return result;
}

}  // namespace esf
