// What fusing frames gains: generated scene sequences (esf record-scenes) played through
// segmentation, recognition and tracking, each true object scored by its own frame and by its
// track after 1, 10 and 30 frames (esf/evaluation/scene_sequences.hpp).
//
//   live_fusion DB DIR [--threads N]
//
// Use model groups the database does not hold:
//   esf train ROOT -o held_out.sqlite --other-folds 0/3
//   esf record-scenes ROOT -o seq --fold 0/3 -n 20 --frames 30

#include <cstdio>
#include <cstdlib>
#include <string>

#include "esf/evaluation/scene_sequences.hpp"

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: live_fusion DB DIR [--threads N]\n");
        return 1;
    }
    esf::RecognizerOptions options;
    options.threads = argc >= 5 && std::string(argv[3]) == "--threads" ? std::atoi(argv[4]) : 0;
    try {
        const esf::Recognizer recognizer(argv[1], options);
        esf::SequenceFusionOptions fusion;
        fusion.segmentation.threads = options.threads;
        const esf::SequenceFusionResult r =
            esf::evaluate_scene_sequences(recognizer, argv[2], fusion);
        auto pct = [](std::size_t n, std::size_t d) {
            return d ? 100.0 * static_cast<double>(n) / static_cast<double>(d) : 0.0;
        };
        std::printf(
            "%zu frames in %.1f s (%.1f frames/s); single frames: %.1f %% of %zu objects "
            "named right\n",
            r.frames, r.seconds, static_cast<double>(r.frames) / r.seconds,
            pct(r.frame_single_right, r.frame_objects), r.frame_objects);
        std::printf("%8s %8s %8s %14s %14s\n", "frames", "objects", "found", "that frame %",
                    "fused %");
        for (const esf::SequenceFusionPoint& p : r.points)
            std::printf("%8zu %8zu %8zu %14.1f %14.1f\n", p.frames, p.objects, p.found,
                        pct(p.single_right, p.objects), pct(p.fused_right, p.objects));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "live_fusion: %s\n", e.what());
        return 2;
    }
    return 0;
}
