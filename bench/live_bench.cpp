// Frames per second of esf live's work on one thread, without the driver's pacing: a raw
// 11-bit frame to an organised cloud, segmentation, description and classification of every
// object, and the tracks' update, frame after frame of a recording (read into memory first).
//
//   live_bench --db DB --recording DIR [--threads N] [--fusion models|likelihood] [--no-verify]
//              [--no-prior-fits] [--no-merge-parts]
//              [benchmark flags]
//
// DB: a training database (default $ESF_BENCH_DB or /tmp/esf_all.sqlite); DIR: a recording of
// esf record-scenes, e.g. a mixed table of 5-7 objects:
//   esf record-scenes ../shared/data/meshes -o /tmp/live_seq -n 1 --frames 30 --types mixed
// Counters: frames/s (items), objects per frame.

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "esf/io/kinect_raw.hpp"
#include "esf/io/kinect_recording.hpp"
#include "esf/recognition/object_tracks.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/segmentation/segmentation.hpp"

namespace {

int g_threads = 1;
esf::TrackingOptions g_tracking;
std::unique_ptr<esf::Recognizer> g_recognizer;
std::vector<esf::KinectFrame> g_frames;

void BM_LiveFrame(benchmark::State& state) {
    esf::SegmentationOptions segmentation;
    segmentation.threads = g_threads;
    esf::ObjectTracker tracker(g_tracking);
    std::size_t index = 0, objects = 0;
    for (auto _ : state) {
        const esf::KinectFrame& frame = g_frames[index++ % g_frames.size()];
        const esf::PointCloud cloud = esf::kinect_raw_to_cloud(frame.depth, frame.rgb);
        const esf::TrackedFrame tracked =
            esf::track_frame(*g_recognizer, tracker, cloud, segmentation);
        objects += tracked.scene.objects.size();
        benchmark::DoNotOptimize(tracked.update);
    }
    state.SetItemsProcessed(state.iterations());
    state.counters["objects_per_frame"] =
        static_cast<double>(objects) / static_cast<double>(state.iterations());
    state.counters["frames_per_s"] =
        benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_LiveFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
    std::string db =
        std::getenv("ESF_BENCH_DB") ? std::getenv("ESF_BENCH_DB") : "/tmp/esf_all.sqlite";
    std::string recording;
    bool verify = true;
    bool merge_parts = true;
    std::vector<char*> rest = {argv[0]};
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--db" && i + 1 < argc)
            db = argv[++i];
        else if (arg == "--recording" && i + 1 < argc)
            recording = argv[++i];
        else if (arg == "--threads" && i + 1 < argc)
            g_threads = std::atoi(argv[++i]);
        else if (arg == "--no-verify")
            verify = false;
        else if (arg == "--no-prior-fits")
            g_tracking.prior_fits = false;
        else if (arg == "--no-merge-parts")
            merge_parts = false;
        else if (arg == "--fusion" && i + 1 < argc)
            g_tracking.fusion = esf::parse_enum<esf::FusionRule>(argv[++i]);
        else
            rest.push_back(argv[i]);
    }
    int rest_count = static_cast<int>(rest.size());
    benchmark::Initialize(&rest_count, rest.data());
    if (!std::filesystem::exists(db) || recording.empty()) {
        std::fprintf(stderr,
                     "live_bench: needs --db DB (%s is missing?) and --recording DIR (esf "
                     "record-scenes ROOT -o DIR -n 1 --types mixed)\n",
                     db.c_str());
        return 1;
    }
    esf::RecognizerOptions options;
    options.threads = g_threads;
    options.verify = verify;
    options.merge_parts = merge_parts;
    g_recognizer = std::make_unique<esf::Recognizer>(db, options);
    esf::KinectRecordingReader reader(recording);
    while (auto frame = reader.next()) g_frames.push_back(std::move(*frame));
    std::fprintf(stderr,
                 "live_bench: %s, %zu frames of %s, %d thread(s), fusion rule %s, "
                 "verification: %s, prior fits %s\n",
                 db.c_str(), g_frames.size(), recording.c_str(), g_threads,
                 esf::to_string(g_tracking.fusion), g_recognizer->info().verification.c_str(),
                 g_tracking.prior_fits ? "on" : "off");
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
