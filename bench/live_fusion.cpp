// What fusing frames gains: generated scene sequences (esf record-scenes) played through
// segmentation, recognition and tracking, each true object scored by its own frame and by its
// track, in every frame and after 1, 10 and 30 frames (esf/evaluation/scene_sequences.hpp).
//
//   live_fusion DB DIR [--threads N] [--fusion models|likelihood] [--no-verify]
//               [--no-prior-fits] [--no-merge-parts] [--match-distance M] [--max-misses N]
//               [--objects FILE]
//
// --objects FILE: one tab-separated row per true object of every frame, for studies of fusion
// rules: sequence, frame, object, true class, track, track's class, points (0: not found), the
// frame's class and fit score, then each candidate verification fits to the object afresh
// (without the track's prior fit) as class:model:score:verified.
//
// Use model groups the database does not hold:
//   esf train ROOT -o held_out.sqlite --other-folds 0/3
//   esf record-scenes ROOT -o seq --fold 0/3 -n 20 --frames 30
// Objects of a class the database has no model of are counted (and never named right).

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "candidate_fits.hpp"
#include "esf/evaluation/scene_sequences.hpp"

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr,
                     "usage: live_fusion DB DIR [--threads N] [--fusion models|likelihood] "
                     "[--no-verify] [--no-prior-fits] [--no-merge-parts] [--match-distance M] "
                     "[--max-misses N] [--objects FILE]\n");
        return 1;
    }
    esf::RecognizerOptions options;
    esf::SequenceFusionOptions fusion;
    std::string objects_path;
    try {
        for (int i = 3; i < argc; ++i) {
            const std::string arg = argv[i];
            if (arg == "--no-verify" || arg == "--no-prior-fits") {
                (arg == "--no-verify" ? options.verify : fusion.tracking.prior_fits) = false;
                continue;
            }
            if (arg == "--no-merge-parts") {
                options.merge_parts = false;
                continue;
            }
            if (i + 1 >= argc) throw std::invalid_argument(arg + " needs a value");
            if (arg == "--threads")
                options.threads = std::atoi(argv[++i]);
            else if (arg == "--match-distance")
                fusion.tracking.match_distance = std::atof(argv[++i]);
            else if (arg == "--max-misses")
                fusion.tracking.max_misses = std::atoi(argv[++i]);
            else if (arg == "--objects")
                objects_path = argv[++i];
            else if (arg == "--fusion")
                fusion.tracking.fusion = esf::parse_enum<esf::FusionRule>(argv[++i]);
            else
                throw std::invalid_argument("unknown option " + arg);
        }
        const esf::Recognizer recognizer(argv[1], options);
        fusion.segmentation.threads = options.threads;
        std::unique_ptr<std::ofstream> rows;
        if (!objects_path.empty()) {
            rows = std::make_unique<std::ofstream>(objects_path);
            if (!*rows) throw std::runtime_error("cannot write " + objects_path);
            fusion.on_object = [&](const esf::SequenceFrameObject& o) {
                std::ofstream& out = *rows;
                out << o.sequence << '\t' << o.frame << '\t' << o.object_id << '\t' << o.true_class
                    << '\t' << o.track << '\t' << (o.track_class.empty() ? "-" : o.track_class)
                    << '\t';
                const esf::RecognizedObject* found = o.found;
                if (!found || !found->classified()) {
                    out << (found ? found->cluster.points.size() : 0) << "\t-\t0\n";
                    return;
                }
                const esf::Classification& c = found->classification;
                out << found->cluster.points.size() << '\t' << c.class_name << '\t'
                    << (c.fit ? c.fit->score() : 0.0);
                if (const std::optional<esf::bench::CandidateFits> fitted =
                        esf::bench::fit_candidates(recognizer, found->cluster.points, o.cloud)) {
                    for (const esf::CandidateFit& f : fitted->fits) {
                        const esf::NeighbourView& n = fitted->knn.neighbours[f.neighbour];
                        out << '\t' << n.class_name << ':' << n.model_name << ':'
                            << f.fit.fit.score() - f.shape_term << ':' << (f.fit.verified ? 1 : 0);
                    }
                }
                out << '\n';
            };
        }
        const esf::SequenceFusionResult r =
            esf::evaluate_scene_sequences(recognizer, argv[2], fusion);
        auto pct = [](std::size_t n, std::size_t d) {
            return d ? 100.0 * static_cast<double>(n) / static_cast<double>(d) : 0.0;
        };
        std::printf(
            "%zu frames in %.1f s (%.1f frames/s), fusion rule %s, %s, prior "
            "fits %s\n",
            r.frames, r.seconds, static_cast<double>(r.frames) / r.seconds,
            esf::to_string(fusion.tracking.fusion), recognizer.info().verification.c_str(),
            fusion.tracking.prior_fits ? "on" : "off");
        std::printf(
            "every frame: %zu objects (%zu of a class without a model in the database), named "
            "right by their frame %.1f %%, by their track %.1f %%, by one of their frames so far "
            "%.1f %% (the most a rule choosing among the frames' classes could reach)\n",
            r.frame_objects, r.frame_unknown, pct(r.frame_single_right, r.frame_objects),
            pct(r.frame_fused_right, r.frame_objects), pct(r.frame_any_right, r.frame_objects));
        std::printf(
            "objects: %zu, named right in at most a tenth of their frames %zu, in at least nine "
            "tenths %zu\n",
            r.objects, r.objects_rarely_right, r.objects_mostly_right);
        std::printf("%8s %8s %8s %8s %14s %14s %14s\n", "frames", "objects", "unknown", "found",
                    "that frame %", "fused %", "any frame %");
        for (const esf::SequenceFusionPoint& p : r.points)
            std::printf("%8zu %8zu %8zu %8zu %14.1f %14.1f %14.1f\n", p.frames, p.objects,
                        p.unknown, p.found, pct(p.single_right, p.objects),
                        pct(p.fused_right, p.objects), pct(p.any_right, p.objects));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "live_fusion: %s\n", e.what());
        return 2;
    }
    return 0;
}
