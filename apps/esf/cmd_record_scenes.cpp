// esf record-scenes : Kinect recordings (fakenect's format) of generated scene sequences, or of
// organised point clouds such as the shared real scenes, for esf live and fakenect.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "cli_generated_scenes.hpp"
#include "commands.hpp"
#include "esf/evaluation/scene_sequences.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/io/kinect_raw.hpp"
#include "esf/io/kinect_recording.hpp"

namespace esf::cli {

namespace {

struct RecordScenesArgs {
    std::string root;
    std::vector<std::string> clouds;
    std::string output;
    std::size_t sequences = 10;
    std::size_t frames = 30;
    double sweep = 30.0;
    double frame_rate = 30.0;
    GeneratedSceneArgs generated;
};

/// Each cloud becomes DIR/<its name>/: the same frame `frames` times.
void record_clouds(const RecordScenesArgs& args) {
    for (const std::string& file : args.clouds) {
        const PointCloud cloud = read_cloud(file);
        if (cloud.width != static_cast<std::uint32_t>(kKinectFrameWidth) ||
            cloud.height != static_cast<std::uint32_t>(kKinectFrameHeight))
            throw std::invalid_argument(
                file + ": a recording needs an organised 640 x 480 cloud, got " +
                std::to_string(cloud.width) + " x " + std::to_string(cloud.height));
        const std::string folder =
            (std::filesystem::path(args.output) / std::filesystem::path(file).stem()).string();
        KinectRecordingWriter writer(folder);
        KinectFrame frame;
        frame.depth = kinect_cloud_to_raw(cloud);
        frame.rgb = kinect_cloud_to_rgb(cloud);
        for (std::size_t f = 0; f < args.frames; ++f) {
            frame.time = 1.0 + static_cast<double>(f) / args.frame_rate;
            frame.timestamp = static_cast<std::uint32_t>(f * 2000000u);
            writer.add(frame);
        }
        writer.finish();
        std::printf("%s: %zu frames of %s\n", folder.c_str(), args.frames, file.c_str());
    }
}

void run_record_scenes(const RecordScenesArgs& args) {
    if (args.root.empty() == args.clouds.empty())
        throw CLI::ValidationError("record-scenes", "give either ROOT or --cloud FILE...");
    if (!args.clouds.empty()) return record_clouds(args);
    SceneSequenceOptions options;
    options.sequences = args.sequences;
    options.frames = args.frames;
    options.sweep = args.sweep;
    options.frame_rate = args.frame_rate;
    set_generated_scene_options(args.generated, options);
    std::optional<Progress> bar;
    options.progress = [&](std::size_t done, std::size_t total) {
        if (!bar) bar.emplace("sequences", total);
        bar->update(done);
    };
    const SceneSequenceSet set = generate_scene_sequences(args.root, args.output, options);
    if (bar) bar->finish();
    std::printf("%s: %zu sequences of %zu frames, %zu models, %zu objects; truth %s\n",
                args.output.c_str(), set.folders.size(), args.frames, set.models, set.objects,
                set.truth.c_str());
    std::printf("  play: fakenect %s esf live DB\n", set.folders.front().c_str());
}

}  // namespace

void add_record_scenes_command(CLI::App& app) {
    auto args = std::make_shared<RecordScenesArgs>();
    CLI::App* cmd = add_command(
        app, "record-scenes", "Write Kinect recordings of generated or real table scenes",
        "Kinect recordings for esf live and fakenect (fakenect-record's format: INDEX.txt, raw "
        "11-bit depth d-*.pgm, colour r-*.ppm): from ROOT, --sequences generated tables (as "
        "esf generate-scenes, without walls and edges) each seen by a camera turning --sweep "
        "degrees about the table over --frames frames, in DIR/sequence_NNN/, with "
        "DIR/sequences.json (objects, classes, cameras, per frame each object's centroid); or "
        "from organised 640 x 480 clouds (--cloud, e.g. the shared real scenes), each frame "
        "--frames times in DIR/<name>/.");
    cmd->add_option("root", args->root, "Folder of <category>/<model>.<ext> meshes")
        ->check(CLI::ExistingDirectory);
    cmd->add_option("--cloud", args->clouds, "Organised clouds to record instead (.pcd, ...)")
        ->check(CLI::ExistingFile);
    cmd->add_option("-o,--output", args->output, "Output folder (created)")->required();
    cmd->add_option("-n,--sequences", args->sequences, "Number of sequences")
        ->check(CLI::Range(1, 10000))
        ->capture_default_str();
    cmd->add_option("--frames", args->frames, "Frames per recording")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    cmd->add_option("--sweep", args->sweep, "Degrees the camera turns over a sequence")
        ->check(CLI::Range(0.0, 360.0))
        ->capture_default_str();
    cmd->add_option("--frame-rate", args->frame_rate, "Frames a second of the recording's clock")
        ->check(CLI::Range(0.1, 1000.0))
        ->capture_default_str();
    add_generated_scene_options(*cmd, args->generated);
    add_generated_scene_model_options(*cmd, args->generated);
    cmd->callback([args] { run_record_scenes(*args); });
}

}  // namespace esf::cli
