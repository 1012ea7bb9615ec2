#pragma once
// Output shared by esf classify and esf scene: JSON of classifications and the recogniser's
// command-line options.

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_common.hpp"
#include "core/number_text.hpp"
#include "esf/recognition/recognizer.hpp"

namespace esf::cli {

struct RecognizerArgs {
    std::string database;
    RecognizerOptions options;
    bool no_weights = false;
    bool every_view = false;
};

/// --no-verify, --verify-meshes ROOT, --candidates N, --accept-score S, --shape-weight W,
/// --fixed-sizes, --two-way-icp, --no-merge-parts, --verify-within-class:
/// hypothesis verification (on by default, with the surfaces the database stores).
inline void add_verification_options(CLI::App& cmd, RecognizerOptions& options) {
    cmd.add_flag_callback(
        "--no-verify", [&options] { options.verify = false; },
        "k-NN only: do not align the nearest models to the points (default: the best "
        "fit of the nearest models names class, model and 6-DoF pose, with its fit)");
    cmd.add_option("--verify-meshes", options.verification_meshes,
                   "Verify with the meshes of ROOT (the folder DB was trained from), for a "
                   "database trained before esf stored the models' surfaces")
        ->check(CLI::ExistingDirectory);
    cmd.add_option("--candidates", options.verification.candidates,
                   "Distinct nearest models aligned to each object")
        ->check(CLI::Range(1, 50))
        ->capture_default_str();
    cmd.add_option("--accept-score", options.verification.accept_score,
                   "A verified fit scoring this much (0.5 x (inliers + support) - violations) "
                   "ends the search: the farther candidates are not fitted (2: fit them all; "
                   "0.7: a fifth faster, a few more cans named box)")
        ->check(CLI::Range(-1.0, 2.0))
        ->capture_default_str();
    cmd.add_option("--shape-weight", options.verification.shape_weight,
                   "Candidates compete by fit score less this times the gap between the "
                   "object's cylinder-box contrast and the model's (0: the score alone)")
        ->check(CLI::Range(0.0, 2.0))
        ->capture_default_str();
    cmd.add_flag_callback(
        "--fixed-sizes", [&options] { options.verification.every_size_free = false; },
        "Fit the size of only the models whose size the catalog guesses (default: every "
        "model's size within [0.8, 1.25] while the candidates compete, the chosen one's pose "
        "then fitted at its model's size)");
    cmd.add_flag_callback(
        "--two-way-icp", [&options] { options.verification.two_way = true; },
        "Pair the object's points with the model too, not only the model's with the object: "
        "better poses and sizes where the database holds the objects' own models (exact CAD "
        "models of known objects); verification takes about 1.5 times as long");
    cmd.add_flag_callback(
        "--no-merge-parts", [&options] { options.merge_parts = false; },
        "Scenes: keep the objects as segmented (default: two neighbouring objects become one "
        "when one model fitted to both explains them better than their own fits)");
    cmd.add_flag_callback(
        "--verify-within-class", [&options] { options.verification.decide_class = false; },
        "Align only models of the class the neighbours named (default: candidates of "
        "any class; the best fit names the class)");
}

/// DB positional, -k, --descriptor, --no-weights, --threads. `args` must outlive `cmd`.
inline void add_recognizer_options(CLI::App& cmd, RecognizerArgs& args) {
    cmd.add_option("database", args.database, "Training database (esf train ... -o DB)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd.add_option("-k", args.options.k,
                   "Nearest models (each by its nearest view) that vote and give the confidence")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd.add_option("--descriptor", args.options.descriptor,
                   "Descriptor kind to use when the database holds several");
    cmd.add_flag("--no-weights", args.no_weights,
                 "Ignore the database's learned sub-histogram weights (plain L1)");
    cmd.add_flag("--every-view", args.every_view,
                 "The k nearest views vote, several of one model among them (default: one view "
                 "per model)");
    add_enum_option(cmd, "--vote", args.options.vote,
                    "How the neighbours name the class: nearest (the nearest one's class; the "
                    "others give the confidence) or majority");
    cmd.add_option("--samplings", args.options.query_samplings,
                   "Describe each query this many times (other seeds) and average")
        ->check(CLI::Range(1, 64))
        ->capture_default_str();
    add_threads_option(cmd, args.options.threads);
    add_verification_options(cmd, args.options);
}

/// One warning line when verification is asked for (the default) and the database cannot give
/// it: trained before esf stored the models' surfaces.
inline void warn_if_unverified(const Recognizer& recognizer) {
    if (recognizer.options().verify && !recognizer.verifies())
        std::fprintf(stderr,
                     "esf: warning: %s: verification %s: k-NN only (train again, or give the "
                     "meshes with --verify-meshes ROOT)\n",
                     recognizer.info().database.c_str(), recognizer.info().verification.c_str());
}

inline RecognizerOptions recognizer_options(const RecognizerArgs& args) {
    RecognizerOptions options = args.options;
    options.use_weights = !args.no_weights;
    options.one_view_per_model = !args.every_view;
    return options;
}

/// A 4x4 pose as 16 numbers, row-major.
inline nlohmann::json pose_json(const Eigen::Matrix4f& pose) {
    nlohmann::json out = nlohmann::json::array();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out.push_back(pose(r, c));
    return out;
}

inline nlohmann::json neighbours_json(const Classification& c) {
    nlohmann::json out = nlohmann::json::array();
    for (const NeighbourView& n : c.neighbours)
        out.push_back({{"class", n.class_name},
                       {"model", n.model_name},
                       {"view", n.view},
                       {"distance", n.distance},
                       {"pose", pose_json(n.pose)}});
    return out;
}

/// class, confidence, model, view, distance, pose, neighbours.
inline void add_classification_json(nlohmann::json& out, const Classification& c) {
    out["class"] = c.class_name;
    out["confidence"] = c.confidence;
    out["model"] = c.best_model;
    out["view"] = c.best_view;
    out["distance"] = c.best_distance;
    out["pose"] = pose_json(c.pose);
    if (c.fit) {
        out["fit"] = {{"inliers", c.fit->inliers},
                      {"support", c.fit->support},
                      {"violations", c.fit->violations},
                      {"rms_mm", c.fit->rms_mm}};
        out["verified"] = c.verified;
    }
    out["neighbours"] = neighbours_json(c);
}

/// For the text tables: "; verified: 83 % inliers, 2 % violations, 2.1 mm" (or "no fit: ..."),
/// empty without verification.
inline std::string fit_text(const Classification& c) {
    if (!c.fit) return {};
    return std::string("; ") + (c.verified ? "verified" : "no fit") + ": " +
           detail::percent_text(c.fit->inliers, 0) + " % inliers, " +
           detail::percent_text(c.fit->violations, 0) + " % violations, " +
           detail::fixed_text(c.fit->rms_mm, 1) + " mm";
}

/// "path: reason", without repeating the path when the reason starts with it.
inline std::string with_file(const std::string& file, const std::string& what) {
    return what.rfind(file, 0) == 0 ? what : file + ": " + what;
}

}  // namespace esf::cli
