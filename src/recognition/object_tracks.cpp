#include "esf/recognition/object_tracks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <tuple>

namespace esf {

namespace {

const std::string kNoClass;

/// kClassLikelihood: the classes of a track from its excess sums, fused log-likelihoods and
/// confidences.
std::vector<FusedClass> fuse_likelihoods(const std::vector<std::pair<std::string, double>>& excess,
                                         std::size_t evidence_frames, double floor) {
    std::vector<FusedClass> classes;
    if (evidence_frames == 0) return classes;
    const double base = static_cast<double>(evidence_frames) * std::log(floor);
    double best = -std::numeric_limits<double>::infinity();
    for (const auto& [name, sum] : excess) {
        classes.push_back({name, base + sum, 0.0, {}, 0});
        best = std::max(best, base + sum);
    }
    double total = 0.0;
    for (const FusedClass& c : classes) total += std::exp(c.score - best);
    for (FusedClass& c : classes) c.confidence = std::exp(c.score - best) / total;
    std::sort(classes.begin(), classes.end(), [](const FusedClass& a, const FusedClass& b) {
        if (a.score != b.score) return a.score > b.score;
        return a.class_name < b.class_name;
    });
    return classes;
}

/// kNearestModels: the classes of a track from its models' tallies (ObjectTracker's private
/// ModelTally, hence the template), each scored by its best model, most likely first (ties:
/// more nearest frames, then the name).
template <typename Tally>
std::vector<FusedClass> fuse_models(const std::vector<Tally>& models) {
    std::vector<FusedClass> classes;
    for (const Tally& m : models) {
        auto it = std::find_if(classes.begin(), classes.end(),
                               [&](const FusedClass& c) { return c.class_name == m.class_name; });
        if (it == classes.end()) {
            classes.push_back({m.class_name, m.score, 0.0, m.model_name, m.nearest});
            continue;
        }
        it->nearest += m.nearest;
        if (m.score > it->score || (m.score == it->score && m.model_name < it->model)) {
            it->score = m.score;
            it->model = m.model_name;
        }
    }
    double total = 0.0;
    std::size_t nearest = 0;
    for (const FusedClass& c : classes) {
        total += c.score;
        nearest += c.nearest;
    }
    for (FusedClass& c : classes)
        c.confidence = total > 0.0 ? c.score / total
                                   : static_cast<double>(c.nearest) / static_cast<double>(nearest);
    std::sort(classes.begin(), classes.end(), [](const FusedClass& a, const FusedClass& b) {
        if (a.score != b.score) return a.score > b.score;
        if (a.nearest != b.nearest) return a.nearest > b.nearest;
        return a.class_name < b.class_name;
    });
    return classes;
}

/// kFrameVotes: the classes of a track from its frames' votes, most votes first (ties: the
/// larger best-model earnings of fuse_models(), then more nearest frames, then the name); a
/// class's score is its votes, its confidence their share.
template <typename Tally>
std::vector<FusedClass> fuse_votes(const std::vector<std::pair<std::string, std::size_t>>& votes,
                                   const std::vector<Tally>& models) {
    const std::vector<FusedClass> by_models = fuse_models(models);
    std::size_t total = 0;
    for (const auto& vote : votes) total += vote.second;
    std::vector<std::pair<FusedClass, double>> classes;  // (class, its best model's earnings)
    for (const auto& [name, count] : votes) {
        FusedClass c{name,
                     static_cast<double>(count),
                     static_cast<double>(count) / static_cast<double>(total),
                     {},
                     0};
        double earnings = 0.0;
        const auto m = std::find_if(by_models.begin(), by_models.end(),
                                    [&](const FusedClass& f) { return f.class_name == name; });
        if (m != by_models.end()) {
            c.model = m->model;
            c.nearest = m->nearest;
            earnings = m->score;
        }
        classes.emplace_back(std::move(c), earnings);
    }
    std::sort(classes.begin(), classes.end(), [](const auto& x, const auto& y) {
        const FusedClass& a = x.first;
        const FusedClass& b = y.first;
        if (a.score != b.score) return a.score > b.score;
        if (x.second != y.second) return x.second > y.second;
        if (a.nearest != b.nearest) return a.nearest > b.nearest;
        return a.class_name < b.class_name;
    });
    std::vector<FusedClass> out;
    for (auto& c : classes) out.push_back(std::move(c.first));
    return out;
}

/// A centroid dropped onto the table plane along its normal (the centroid without a plane).
Eigen::Vector3f table_position(bool plane_found, const Plane& plane, const Eigen::Vector3f& c) {
    return plane_found ? Eigen::Vector3f(c - plane.height(c) * plane.normal) : c;
}

}  // namespace

void validate(const TrackingOptions& options) {
    if (!(std::isfinite(options.match_distance) && options.match_distance > 0.0))
        throw std::invalid_argument("tracking match distance must be positive, got " +
                                    std::to_string(options.match_distance));
    if (options.max_misses < 0)
        throw std::invalid_argument("tracking max misses must not be negative, got " +
                                    std::to_string(options.max_misses));
    if (!(options.evidence_floor > 0.0 && options.evidence_floor < 1.0))
        throw std::invalid_argument("tracking evidence floor must be in (0, 1), got " +
                                    std::to_string(options.evidence_floor));
}

std::vector<ClassEvidence> class_evidence(const Classification& c) {
    std::vector<ClassEvidence> out;
    if (c.neighbours.empty()) return out;
    std::map<std::string, double> p;
    const double share = 0.5 / static_cast<double>(c.neighbours.size());
    for (const NeighbourView& n : c.neighbours) p[n.class_name] += share;
    p[c.neighbours.front().class_name] += 0.5;
    for (const auto& [name, probability] : p) out.push_back({name, probability});
    std::stable_sort(out.begin(), out.end(), [](const ClassEvidence& a, const ClassEvidence& b) {
        return a.probability > b.probability;
    });
    return out;
}

std::vector<ModelEvidence> model_evidence(const Classification& c) {
    std::vector<ModelEvidence> out;
    for (const NeighbourView& n : c.neighbours) {
        const auto same = [&](const ModelEvidence& m) {
            return m.class_name == n.class_name && m.model_name == n.model_name;
        };
        const auto it = std::find_if(out.begin(), out.end(), same);
        if (it == out.end())
            out.push_back({n.class_name, n.model_name, n.distance});
        else
            it->distance = std::min(it->distance, n.distance);
    }
    // Verification may have put the best fit first: nearest first again.
    std::stable_sort(out.begin(), out.end(), [](const ModelEvidence& a, const ModelEvidence& b) {
        return a.distance < b.distance;
    });
    return out;
}

std::vector<ModelScore> model_scores(std::span<const ModelEvidence> models) {
    for (std::size_t i = 0; i < models.size(); ++i) {
        const double d = models[i].distance;
        if (!(std::isfinite(d) && d >= 0.0))
            throw std::invalid_argument("model " + std::to_string(i) + " ('" +
                                        models[i].model_name +
                                        "') has a negative or non-finite distance");
        if (i > 0 && d < models[i - 1].distance)
            throw std::invalid_argument("models must come nearest first, but model " +
                                        std::to_string(i) + " ('" + models[i].model_name +
                                        "') is nearer than the one before it");
    }
    std::vector<ModelScore> out;
    if (models.empty()) return out;
    for (const ModelEvidence& m : models) out.push_back({m.class_name, m.model_name, 0.0});
    const double nearest = models.front().distance, farthest = models.back().distance;
    if (!(farthest > nearest)) {  // one distance for all (k = 1): a plain vote
        out.front().score = 1.0;
        return out;
    }
    double other = farthest;
    for (const ModelEvidence& m : models)
        if (m.class_name != models.front().class_name) {
            other = m.distance;
            break;
        }
    const double weight = other > 0.0 ? 1.0 - nearest / other : 0.0;
    for (std::size_t i = 0; i < models.size(); ++i)
        out[i].score = weight * (1.0 - models[i].distance / farthest);
    return out;
}

std::vector<TrackedObservation> scene_observations(const SceneRecognition& scene) {
    std::vector<TrackedObservation> out;
    out.reserve(scene.objects.size());
    for (const RecognizedObject& o : scene.objects) {
        TrackedObservation t;
        t.position = table_position(scene.plane_found, scene.plane, o.cluster.centroid);
        if (o.classified()) {
            t.evidence = class_evidence(o.classification);
            t.models = model_evidence(o.classification);
            t.class_name = o.classification.class_name;
            const Classification& k = o.classification;
            if (k.verified && k.fit)
                t.fit = FitEvidence{k.class_name, k.best_model, std::max(0.0, k.fit->score()),
                                    k.best_model_id, k.pose};
        }
        out.push_back(std::move(t));
    }
    return out;
}

const std::string& ObjectTrack::class_name() const {
    return classes.empty() ? kNoClass : classes.front().class_name;
}

double ObjectTrack::confidence() const {
    return classes.empty() ? 0.0 : classes.front().confidence;
}

ObjectTracker::ObjectTracker(const TrackingOptions& options) : options_(options) {
    validate(options_);
}

TrackUpdate ObjectTracker::update(const SceneRecognition& scene) {
    const std::vector<TrackedObservation> observations = scene_observations(scene);
    return update(observations);
}

std::vector<std::size_t> ObjectTracker::match(std::span<const Eigen::Vector3f> positions) const {
    // Candidate pairs within the match distance, nearest first (ties: lower track id, then lower
    // object index), each track and each object at most once.
    std::vector<std::tuple<double, std::uint64_t, std::size_t, std::size_t>> pairs;
    for (std::size_t t = 0; t < tracks_.size(); ++t)
        for (std::size_t o = 0; o < positions.size(); ++o) {
            const double d = static_cast<double>((positions[o] - tracks_[t].position).norm());
            if (d <= options_.match_distance) pairs.emplace_back(d, tracks_[t].id, t, o);
        }
    std::sort(pairs.begin(), pairs.end());
    std::vector<bool> track_taken(tracks_.size(), false);
    std::vector<std::size_t> object_track(positions.size(), tracks_.size());
    for (const auto& [d, id, t, o] : pairs) {
        if (track_taken[t] || object_track[o] < tracks_.size()) continue;
        track_taken[t] = true;
        object_track[o] = t;
    }
    return object_track;
}

TrackUpdate ObjectTracker::update(std::span<const TrackedObservation> observations) {
    // The frames' votes break their ties by the nearest models' earnings: both tally them.
    const bool by_votes = options_.fusion == FusionRule::kFrameVotes;
    const bool tally_models = options_.fusion == FusionRule::kNearestModels || by_votes;
    // Checked (and scored) before anything changes, so that a refused frame leaves no trace.
    std::vector<std::vector<ModelScore>> scores(observations.size());
    for (std::size_t i = 0; i < observations.size(); ++i) {
        if (!observations[i].position.allFinite())
            throw std::invalid_argument("tracked object " + std::to_string(i) +
                                        " has a non-finite position");
        if (!tally_models) continue;
        try {
            scores[i] = model_scores(observations[i].models);
        } catch (const std::invalid_argument& e) {
            throw std::invalid_argument("tracked object " + std::to_string(i) + ": " + e.what());
        }
    }
    TrackUpdate result;
    result.frame = frames_;
    result.object_track.assign(observations.size(), 0);

    std::vector<Eigen::Vector3f> positions;
    for (const TrackedObservation& o : observations) positions.push_back(o.position);
    const std::vector<std::size_t> object_track = match(positions);
    std::vector<bool> object_taken(observations.size(), false);
    std::vector<std::size_t> track_object(tracks_.size(), observations.size());
    for (std::size_t o = 0; o < observations.size(); ++o)
        if (object_track[o] < tracks_.size()) {
            object_taken[o] = true;
            track_object[object_track[o]] = o;
        }

    const double log_floor = std::log(options_.evidence_floor);
    auto observe = [&](std::size_t t, std::size_t o) {
        const TrackedObservation& obs = observations[o];
        ObjectTrack& track = tracks_[t];
        track.position = obs.position;
        ++track.frames;
        track.misses = 0;
        track.last_frame = frames_;
        if (obs.fit) track.fit = obs.fit;
        if (tally_models) {
            if (scores[o].empty() && (!by_votes || obs.class_name.empty())) return;
            ++track.evidence_frames;
            std::vector<ModelTally>& tallies = sums_[t].models;
            for (std::size_t i = 0; i < scores[o].size(); ++i) {
                const ModelScore& s = scores[o][i];
                auto it = std::find_if(tallies.begin(), tallies.end(), [&](const ModelTally& m) {
                    return m.class_name == s.class_name && m.model_name == s.model_name;
                });
                if (it == tallies.end()) {
                    tallies.push_back({s.class_name, s.model_name, 0.0, 0});
                    it = tallies.end() - 1;
                }
                it->score += s.score;
                it->nearest += i == 0;
            }
            if (!by_votes) {
                track.classes = fuse_models(tallies);
                return;
            }
            auto& votes = sums_[t].votes;
            if (!obs.class_name.empty()) {
                auto v = std::find_if(votes.begin(), votes.end(),
                                      [&](const auto& p) { return p.first == obs.class_name; });
                if (v == votes.end())
                    votes.emplace_back(obs.class_name, 1);
                else
                    ++v->second;
            }
            track.classes = fuse_votes(votes, tallies);
            return;
        }
        if (obs.evidence.empty()) return;
        ++track.evidence_frames;
        auto& sums = sums_[t].excess;
        for (const ClassEvidence& e : obs.evidence) {
            const double gain =
                std::log(std::max(e.probability, options_.evidence_floor)) - log_floor;
            auto it = std::find_if(sums.begin(), sums.end(),
                                   [&](const auto& s) { return s.first == e.class_name; });
            if (it == sums.end())
                sums.emplace_back(e.class_name, gain);
            else
                it->second += gain;
        }
        track.classes = fuse_likelihoods(sums, track.evidence_frames, options_.evidence_floor);
    };

    // Seen tracks are updated, missed ones age and end past max_misses.
    std::vector<ObjectTrack> kept;
    std::vector<Sums> kept_sums;
    for (std::size_t t = 0; t < tracks_.size(); ++t) {
        if (track_object[t] < observations.size()) {
            observe(t, track_object[t]);
            result.object_track[track_object[t]] = tracks_[t].id;
        } else if (++tracks_[t].misses > static_cast<std::size_t>(options_.max_misses)) {
            result.ended.push_back(tracks_[t]);
            continue;
        }
        kept.push_back(std::move(tracks_[t]));
        kept_sums.push_back(std::move(sums_[t]));
    }
    tracks_ = std::move(kept);
    sums_ = std::move(kept_sums);

    // New tracks for the objects no track took, in the objects' order.
    for (std::size_t o = 0; o < observations.size(); ++o) {
        if (object_taken[o]) continue;
        ObjectTrack track;
        track.id = next_id_++;
        track.first_frame = frames_;
        tracks_.push_back(track);
        sums_.emplace_back();
        observe(tracks_.size() - 1, o);
        result.object_track[o] = track.id;
        result.born.push_back(track.id);
    }
    ++frames_;
    return result;
}

TrackedFrame track_frame(const Recognizer& recognizer, ObjectTracker& tracker,
                         const PointCloud& frame, const SegmentationOptions& segmentation) {
    SegmentationResult segmented = segment_scene(frame, segmentation);
    std::vector<std::optional<PriorFit>> priors;
    if (tracker.options().prior_fits) {
        std::vector<Eigen::Vector3f> positions;
        for (const Cluster& c : segmented.clusters)
            positions.push_back(table_position(segmented.plane_found, segmented.plane, c.centroid));
        const std::vector<std::size_t> track = tracker.match(positions);
        for (const std::size_t t : track) {
            priors.emplace_back();
            if (t >= tracker.tracks().size() || !tracker.tracks()[t].fit) continue;
            const FitEvidence& fit = *tracker.tracks()[t].fit;
            priors.back() = PriorFit{fit.model_id, fit.pose, fit.score};
        }
    }
    TrackedFrame out;
    out.scene = recognizer.recognize(std::move(segmented), frame, priors);
    out.update = tracker.update(out.scene);
    return out;
}

}  // namespace esf
