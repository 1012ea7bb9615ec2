// Fusion rules side by side (a study, not a benchmark): generated scene sequences (esf
// record-scenes) are played once through segmentation, recognition and the tracker; per object
// of every frame it keeps its track, descriptor, k nearest models and distance to every model
// of the database (min over the model's views), then scores each candidate rule on the same
// tracks, as live_fusion scores the tracker's (esf/evaluation/scene_sequences.hpp).
//
//   fusion_study DB DIR [--threads N] [--oracle-tracks] [--objects] [--per-sequence FILE]
//
// Columns: a track's class right after 1, 10 and 30 frames, over every frame, and over the
// frames from the 10th on. "that frame" is the frame alone (the single-frame classification).
// --oracle-tracks: objects are grouped by their true object instead of the tracker's tracks.
// --objects: per true object, the classes its frames named and the rank of its class under
// the summed model distances. --per-sequence FILE: appends per rule the objects named right in
// each sequence (tab-separated), for paired comparisons of rules.
// The rule the tracker uses (FusionRule::kNearestModels) is "nearest models, margin".

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "esf/io/kinect_raw.hpp"
#include "esf/io/kinect_recording.hpp"
#include "esf/recognition/object_tracks.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/segmentation/segmentation.hpp"

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();

/// One object of one frame.
struct Observation {
    bool classified = false;
    std::string nn_class;  ///< the frame's own class
    std::vector<esf::ClassEvidence> evidence;
    std::vector<esf::ModelEvidence> models;  ///< the k nearest, nearest first
    std::vector<float> descriptor;
    std::vector<double> model_distance;  ///< per database model
    std::uint64_t track = 0;
    std::size_t points = 0;
};

/// One true object of one frame, and the object of the frame it was found as.
struct Truth {
    std::string true_class;
    std::uint32_t object_id = 0;
    std::size_t object = kNone;
};

struct Frame {
    std::vector<Observation> objects;
    std::vector<Truth> truth;
};

using Sequence = std::vector<Frame>;
using Track = std::vector<const Observation*>;  // a track's observations so far
using Rule = std::function<std::string(const Track&)>;

struct Database {
    std::vector<std::string> model_class;  ///< per model (index family)
    std::set<std::string> classes;
};

std::string best_of(const std::map<std::string, double>& score) {
    std::string best;
    double b = -std::numeric_limits<double>::infinity();
    for (const auto& [name, s] : score)
        if (s > b) {
            b = s;
            best = name;
        }
    return best;
}

double nearest_distance(const Observation& o) {
    return *std::min_element(o.model_distance.begin(), o.model_distance.end());
}

double l1(const std::vector<float>& a, const std::vector<float>& b) {
    double s = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i)
        s += std::abs(static_cast<double>(a[i]) - static_cast<double>(b[i]));
    return s;
}

std::vector<Sequence> play(const esf::Recognizer& recognizer, const std::string& folder,
                           int threads) {
    const esf::KnnIndex& index = recognizer.classifier().index();
    esf::SegmentationOptions segmentation;
    segmentation.threads = threads;
    nlohmann::json truth;
    {
        std::ifstream in((fs::path(folder) / "sequences.json").string());
        if (!in) throw std::runtime_error(folder + "/sequences.json cannot be read");
        truth = nlohmann::json::parse(in);
    }
    std::vector<Sequence> sequences;
    for (const nlohmann::json& sequence : truth.at("sequences")) {
        std::map<std::uint32_t, std::string> class_of;
        for (const nlohmann::json& o : sequence.at("objects"))
            class_of[o.at("object_id").get<std::uint32_t>()] = o.at("class").get<std::string>();
        esf::KinectRecordingReader reader(
            (fs::path(folder) / sequence.at("folder").get<std::string>()).string());
        esf::ObjectTracker tracker;
        Sequence seq;
        for (const nlohmann::json& frame_truth : sequence.at("frames")) {
            const std::optional<esf::KinectFrame> frame = reader.next();
            if (!frame) throw std::runtime_error("a recording has fewer frames than its truth");
            const esf::PointCloud cloud = esf::kinect_raw_to_cloud(frame->depth, frame->rgb);
            esf::SegmentationResult segments = esf::segment_scene(cloud, segmentation);
            std::vector<esf::Points> clouds;
            for (const esf::Cluster& c : segments.clusters) clouds.push_back(c.points);
            const esf::SceneRecognition scene = recognizer.recognize(std::move(segments));
            const esf::TrackUpdate update = tracker.update(scene);
            const std::vector<esf::QueryDescriptor> described = recognizer.describe_batch(clouds);
            Frame out;
            for (std::size_t i = 0; i < scene.objects.size(); ++i) {
                Observation o;
                o.track = update.object_track[i];
                o.points = scene.objects[i].cluster.points.size();
                o.classified = scene.objects[i].classified();
                if (o.classified) {
                    const esf::Classification& c = scene.objects[i].classification;
                    o.nn_class = c.class_name;
                    o.evidence = esf::class_evidence(c);
                    o.models = esf::model_evidence(c);
                    o.descriptor = described[i].signatures;
                    o.model_distance.assign(index.families(),
                                            std::numeric_limits<double>::infinity());
                    for (std::size_t r = 0; r < index.rows(); ++r) {
                        double& d = o.model_distance[index.family_of(index.view_of(r))];
                        d = std::min(d, index.distance(o.descriptor, r));
                    }
                }
                out.objects.push_back(std::move(o));
            }
            for (const nlohmann::json& o : frame_truth.at("objects")) {
                if (o.at("centroid").is_null()) continue;
                const Eigen::Vector3f c(o["centroid"][0].get<float>(),
                                        o["centroid"][1].get<float>(),
                                        o["centroid"][2].get<float>());
                Truth t;
                t.object_id = o.at("object_id").get<std::uint32_t>();
                t.true_class = class_of.at(t.object_id);
                double best = 0.05;  // as evaluate_scene_sequences
                for (std::size_t i = 0; i < scene.objects.size(); ++i) {
                    const double d =
                        static_cast<double>((scene.objects[i].cluster.centroid - c).norm());
                    if (d <= best) {
                        best = d;
                        t.object = i;
                    }
                }
                out.truth.push_back(t);
            }
            seq.push_back(std::move(out));
        }
        sequences.push_back(std::move(seq));
        std::fprintf(stderr, ".");
    }
    std::fprintf(stderr, "\n");
    return sequences;
}

std::vector<std::pair<std::string, Rule>> candidate_rules(const esf::KnnIndex& index,
                                                          const Database& db) {
    const std::size_t models = db.model_class.size();
    std::vector<std::pair<std::string, Rule>> rules;
    rules.emplace_back("that frame", [](const Track& track) {
        return track.back()->classified ? track.back()->nn_class : std::string();
    });
    for (const double floor : {0.01, 0.1})
        rules.emplace_back(
            floor == 0.01 ? "class likelihood (former rule)" : "class likelihood, floor 0.1",
            [floor](const Track& track) {
                std::map<std::string, double> s;
                for (const Observation* o : track)
                    for (const esf::ClassEvidence& e : o->evidence)
                        s[e.class_name] += std::log(std::max(e.probability, floor) / floor);
                return best_of(s);
            });
    rules.emplace_back("vote of the frames' classes", [](const Track& track) {
        std::map<std::string, double> s;
        double later = 0.0;  // ties: the later frame
        for (const Observation* o : track)
            if (o->classified) s[o->nn_class] += 1.0 + (later += 1e-6);
        return best_of(s);
    });
    rules.emplace_back("vote of the k neighbours", [](const Track& track) {
        std::map<std::string, double> s;
        for (const Observation* o : track)
            for (const esf::ModelEvidence& m : o->models) s[m.class_name] += 1.0;
        return best_of(s);
    });
    rules.emplace_back("distinct nearest models", [](const Track& track) {
        std::map<std::string, std::set<std::string>> seen;
        std::map<std::string, double> votes;
        for (const Observation* o : track)
            if (o->classified) {
                seen[o->models.front().class_name].insert(o->models.front().model_name);
                votes[o->models.front().class_name] += 1.0;
            }
        std::map<std::string, double> s;
        for (const auto& [name, m] : seen)
            s[name] = static_cast<double>(m.size()) + 1e-3 * votes[name];
        return best_of(s);
    });
    // Summed distance to every model (min over its views), per frame as is, relative to the
    // frame's nearest, or truncated at the frame's k-th nearest model.
    enum class Norm { kPlain, kNearest, kLogNearest };
    auto model_sum = [&db, models](Norm norm, std::size_t truncate, bool novelty) {
        return [&db, models, norm, truncate, novelty](const Track& track) {
            std::vector<double> sum(models, 0.0);
            std::vector<const Observation*> seen;
            for (const Observation* o : track) {
                if (!o->classified) continue;
                double weight = 1.0;
                if (novelty && !seen.empty()) {  // distance to the nearest earlier view, / 0.1
                    double d = std::numeric_limits<double>::infinity();
                    for (const Observation* p : seen)
                        d = std::min(d, l1(o->descriptor, p->descriptor));
                    weight = std::min(1.0, d / 0.1);
                }
                seen.push_back(o);
                std::vector<double> d = o->model_distance;
                if (truncate > 0 && truncate < models) {
                    std::vector<double> sorted = d;
                    std::nth_element(sorted.begin(),
                                     sorted.begin() + static_cast<std::ptrdiff_t>(truncate - 1),
                                     sorted.end());
                    for (double& v : d) v = std::min(v, sorted[truncate - 1]);
                }
                const double d1 = nearest_distance(*o);
                for (std::size_t m = 0; m < models; ++m) {
                    double v = d[m];
                    if (norm == Norm::kNearest) v /= d1;
                    if (norm == Norm::kLogNearest) v = std::log(v / d1);
                    sum[m] += weight * v;
                }
            }
            if (seen.empty()) return std::string();
            return db.model_class[static_cast<std::size_t>(
                std::min_element(sum.begin(), sum.end()) - sum.begin())];
        };
    };
    rules.emplace_back("model distance sum", model_sum(Norm::kPlain, 0, false));
    rules.emplace_back("model distance sum, / nearest", model_sum(Norm::kNearest, 0, false));
    rules.emplace_back("model distance sum, log / nearest", model_sum(Norm::kLogNearest, 0, false));
    rules.emplace_back("model distance sum, / nearest, novelty",
                       model_sum(Norm::kNearest, 0, true));
    rules.emplace_back("model distance sum, truncated at 40", model_sum(Norm::kPlain, 40, false));
    rules.emplace_back("class distance sum", [models, &db](const Track& track) {
        std::map<std::string, double> s;
        for (const Observation* o : track) {
            if (!o->classified) continue;
            std::map<std::string, double> d;
            for (std::size_t m = 0; m < models; ++m) {
                auto it = d.find(db.model_class[m]);
                if (it == d.end() || o->model_distance[m] < it->second)
                    d[db.model_class[m]] = o->model_distance[m];
            }
            for (const auto& [name, v] : d) s[name] -= v;
        }
        return best_of(s);
    });
    rules.emplace_back("mean descriptor", [&index, &db](const Track& track) {
        std::vector<float> mean;
        std::size_t n = 0;
        for (const Observation* o : track) {
            if (!o->classified) continue;
            if (mean.empty()) mean.assign(o->descriptor.size(), 0.0f);
            for (std::size_t i = 0; i < mean.size(); ++i) mean[i] += o->descriptor[i];
            ++n;
        }
        if (n == 0) return std::string();
        for (float& v : mean) v /= static_cast<float>(n);
        return db.model_class[index.family_of(index.search(mean, 1).neighbours.front().view)];
    });
    for (const double T : {0.02, 0.05})
        rules.emplace_back("soft-min class likelihood, T " + std::to_string(T).substr(0, 4),
                           [T, models, &db](const Track& track) {
                               std::map<std::string, double> s;
                               for (const Observation* o : track) {
                                   if (!o->classified) continue;
                                   const double d1 = nearest_distance(*o);
                                   std::map<std::string, double> p;
                                   double z = 0.0;
                                   for (std::size_t m = 0; m < models; ++m) {
                                       const double e =
                                           std::exp(-(o->model_distance[m] / d1 - 1.0) / T);
                                       p[db.model_class[m]] += e;
                                       z += e;
                                   }
                                   for (const auto& [name, v] : p)
                                       s[name] += std::log(std::max(v / z, 1e-300));
                               }
                               return best_of(s);
                           });
    // From the k nearest models alone: each earns weight x gain per frame, a class scores by
    // its best model (or, "class sum", by the sum of its models).
    enum class Gain { kOverNearest, kOverKth, kLog };
    enum class Weight { kOne, kMargin, kPoints };
    auto earnings = [](Gain gain, Weight weight, bool class_sum) {
        return [gain, weight, class_sum](const Track& track) {
            std::map<std::pair<std::string, std::string>, double> sum;
            std::size_t most_points = 0;
            for (const Observation* o : track)
                if (o->classified) most_points = std::max(most_points, o->points);
            for (const Observation* o : track) {
                if (!o->classified) continue;
                const std::vector<esf::ModelEvidence>& m = o->models;
                const double d1 = m.front().distance, dk = m.back().distance;
                double w = 1.0;
                if (weight == Weight::kMargin) {
                    double other = dk;
                    for (const esf::ModelEvidence& e : m)
                        if (e.class_name != m.front().class_name) {
                            other = e.distance;
                            break;
                        }
                    w = other > 0.0 ? 1.0 - d1 / other : 0.0;
                }
                if (weight == Weight::kPoints)
                    w = static_cast<double>(o->points) / static_cast<double>(most_points);
                for (const esf::ModelEvidence& e : m) {
                    double g = (dk - e.distance) / dk;
                    if (gain == Gain::kOverNearest) g = (dk - e.distance) / d1;
                    if (gain == Gain::kLog) g = std::log(dk / e.distance);
                    sum[{e.class_name, e.model_name}] += w * g;
                }
            }
            std::map<std::string, double> s;
            for (const auto& [model, v] : sum) {
                double& c = s[model.first];
                c = class_sum ? c + v : std::max(c, v);
            }
            return best_of(s);
        };
    };
    rules.emplace_back("nearest models", earnings(Gain::kOverKth, Weight::kOne, false));
    rules.emplace_back("nearest models, margin", earnings(Gain::kOverKth, Weight::kMargin, false));
    rules.emplace_back("nearest models, margin, class sum",
                       earnings(Gain::kOverKth, Weight::kMargin, true));
    rules.emplace_back("nearest models, points", earnings(Gain::kOverKth, Weight::kPoints, false));
    rules.emplace_back("nearest models / d1, margin",
                       earnings(Gain::kOverNearest, Weight::kMargin, false));
    rules.emplace_back("nearest models log, margin", earnings(Gain::kLog, Weight::kMargin, false));
    return rules;
}

/// Per true object: the classes its frames named, and the rank of its class when every model's
/// distance (relative to each frame's nearest) is summed over its frames.
void print_objects(const std::vector<Sequence>& sequences, const Database& db) {
    const std::size_t models = db.model_class.size();
    for (std::size_t s = 0; s < sequences.size(); ++s) {
        std::map<std::uint32_t, std::map<std::string, int>> named;
        std::map<std::uint32_t, std::string> true_class;
        std::map<std::uint32_t, std::vector<double>> sum;
        for (const Frame& frame : sequences[s])
            for (const Truth& t : frame.truth) {
                true_class[t.object_id] = t.true_class;
                if (t.object == kNone) {
                    ++named[t.object_id]["(not found)"];
                    continue;
                }
                const Observation& o = frame.objects[t.object];
                ++named[t.object_id][o.classified ? o.nn_class : "(no class)"];
                if (!o.classified) continue;
                std::vector<double>& v = sum[t.object_id];
                if (v.empty()) v.assign(models, 0.0);
                for (std::size_t m = 0; m < models; ++m)
                    v[m] += o.model_distance[m] / nearest_distance(o);
            }
        for (const auto& [id, counts] : named) {
            std::printf("sequence %zu object %u %s:", s, id, true_class[id].c_str());
            for (const auto& [name, n] : counts) std::printf(" %s %d", name.c_str(), n);
            if (!sum[id].empty()) {
                std::map<std::string, double> best;
                for (std::size_t m = 0; m < models; ++m) {
                    auto it = best.find(db.model_class[m]);
                    if (it == best.end() || sum[id][m] < it->second)
                        best[db.model_class[m]] = sum[id][m];
                }
                const auto own = best.find(true_class[id]);
                if (own != best.end()) {
                    std::size_t rank = 1;
                    for (const auto& [name, v] : best) rank += v < own->second;
                    std::printf(" | summed distances: its class ranks %zu of %zu", rank,
                                best.size());
                }
            }
            std::printf("\n");
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr,
                     "usage: fusion_study DB DIR [--threads N] [--oracle-tracks] [--objects] "
                     "[--per-sequence FILE]\n");
        return 1;
    }
    esf::RecognizerOptions options;
    bool oracle = false, objects = false;
    std::string per_sequence;
    for (int i = 3; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--threads" && i + 1 < argc) {
            options.threads = std::atoi(argv[++i]);
        } else if (arg == "--oracle-tracks") {
            oracle = true;
        } else if (arg == "--objects") {
            objects = true;
        } else if (arg == "--per-sequence" && i + 1 < argc) {
            per_sequence = argv[++i];
        } else {
            std::fprintf(stderr, "fusion_study: unknown option %s\n", arg.c_str());
            return 1;
        }
    }
    try {
        const esf::Recognizer recognizer(argv[1], options);
        const esf::KnnIndex& index = recognizer.classifier().index();
        Database db;
        db.model_class.assign(index.families(), "");
        const auto& labels = recognizer.classifier().labels();
        for (std::size_t v = 0; v < labels.size(); ++v) {
            db.model_class[index.family_of(static_cast<std::uint32_t>(v))] = labels[v].class_name;
            db.classes.insert(labels[v].class_name);
        }
        std::vector<Sequence> sequences = play(recognizer, argv[2], options.threads);
        if (oracle)
            for (Sequence& seq : sequences)
                for (Frame& frame : seq)
                    for (const Truth& t : frame.truth)
                        if (t.object != kNone)
                            frame.objects[t.object].track = 1000000 + t.object_id;
        if (objects) print_objects(sequences, db);

        // Objects, unknown classes, and the share some frame of the track so far named right.
        std::size_t total = 0, unknown = 0, some_frame = 0;
        for (const Sequence& seq : sequences) {
            std::map<std::uint64_t, Track> tracks;
            for (const Frame& frame : seq) {
                for (const Observation& o : frame.objects) tracks[o.track].push_back(&o);
                for (const Truth& t : frame.truth) {
                    ++total;
                    unknown += !db.classes.contains(t.true_class);
                    if (t.object == kNone) continue;
                    bool any = false;
                    for (const Observation* o : tracks[frame.objects[t.object].track])
                        any |= o->classified && o->nn_class == t.true_class;
                    some_frame += any;
                }
            }
        }
        auto pct = [](std::size_t n, std::size_t d) {
            return d ? 100.0 * static_cast<double>(n) / static_cast<double>(d) : 0.0;
        };
        std::printf(
            "%zu true objects over all frames, %zu of a class the database lacks; some "
            "frame of the track so far named it right: %.1f %%\n",
            total, unknown, pct(some_frame, total));
        std::printf("%-40s %7s %7s %7s %7s %7s\n", "rule", "@1", "@10", "@30", "every", ">=10");
        const std::vector<std::size_t> checkpoints = {1, 10, 30};
        for (const auto& [name, rule] : candidate_rules(index, db)) {
            std::vector<std::size_t> right(checkpoints.size(), 0), seen(checkpoints.size(), 0);
            std::size_t every = 0, late = 0, late_seen = 0;
            std::vector<std::size_t> per_seq;
            for (const Sequence& seq : sequences) {
                per_seq.push_back(0);
                std::map<std::uint64_t, Track> tracks;
                for (std::size_t f = 0; f < seq.size(); ++f) {
                    const Frame& frame = seq[f];
                    for (const Observation& o : frame.objects) tracks[o.track].push_back(&o);
                    std::map<std::uint64_t, std::string> fused;
                    for (const Observation& o : frame.objects)
                        fused[o.track] = rule(tracks[o.track]);
                    for (const Truth& t : frame.truth) {
                        const bool ok = t.object != kNone &&
                                        fused[frame.objects[t.object].track] == t.true_class;
                        every += ok;
                        per_seq.back() += ok;
                        if (f + 1 >= 10) {
                            ++late_seen;
                            late += ok;
                        }
                        for (std::size_t c = 0; c < checkpoints.size(); ++c)
                            if (checkpoints[c] == f + 1) {
                                ++seen[c];
                                right[c] += ok;
                            }
                    }
                }
            }
            std::printf("%-40s %7.1f %7.1f %7.1f %7.1f %7.1f\n", name.c_str(),
                        pct(right[0], seen[0]), pct(right[1], seen[1]), pct(right[2], seen[2]),
                        pct(every, total), pct(late, late_seen));
            if (!per_sequence.empty()) {
                std::ofstream out(per_sequence, std::ios::app);
                out << name;
                for (const std::size_t v : per_seq) out << '\t' << v;
                out << '\n';
            }
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "fusion_study: %s\n", e.what());
        return 2;
    }
    return 0;
}
