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

/// The classes of a track from its excess sums: fused log-likelihoods and confidences.
std::vector<FusedClass> fuse(const std::vector<std::pair<std::string, double>>& excess,
                             std::size_t evidence_frames, double floor) {
    std::vector<FusedClass> classes;
    if (evidence_frames == 0) return classes;
    const double base = static_cast<double>(evidence_frames) * std::log(floor);
    double best = -std::numeric_limits<double>::infinity();
    for (const auto& [name, sum] : excess) {
        classes.push_back({name, base + sum, 0.0});
        best = std::max(best, base + sum);
    }
    double total = 0.0;
    for (const FusedClass& c : classes) total += std::exp(c.log_likelihood - best);
    for (FusedClass& c : classes) c.confidence = std::exp(c.log_likelihood - best) / total;
    std::sort(classes.begin(), classes.end(), [](const FusedClass& a, const FusedClass& b) {
        if (a.log_likelihood != b.log_likelihood) return a.log_likelihood > b.log_likelihood;
        return a.class_name < b.class_name;
    });
    return classes;
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

std::vector<TrackedObservation> scene_observations(const SceneRecognition& scene) {
    std::vector<TrackedObservation> out;
    out.reserve(scene.objects.size());
    for (const RecognizedObject& o : scene.objects) {
        TrackedObservation t;
        const Eigen::Vector3f& c = o.cluster.centroid;
        t.position =
            scene.plane_found ? Eigen::Vector3f(c - scene.plane.height(c) * scene.plane.normal) : c;
        if (o.classified()) t.evidence = class_evidence(o.classification);
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

TrackUpdate ObjectTracker::update(std::span<const TrackedObservation> observations) {
    for (std::size_t i = 0; i < observations.size(); ++i)
        if (!observations[i].position.allFinite())
            throw std::invalid_argument("tracked object " + std::to_string(i) +
                                        " has a non-finite position");
    TrackUpdate result;
    result.frame = frames_;
    result.object_track.assign(observations.size(), 0);

    // Candidate pairs within the match distance, nearest first.
    std::vector<std::tuple<double, std::uint64_t, std::size_t, std::size_t>> pairs;
    for (std::size_t t = 0; t < tracks_.size(); ++t)
        for (std::size_t o = 0; o < observations.size(); ++o) {
            const double d =
                static_cast<double>((observations[o].position - tracks_[t].position).norm());
            if (d <= options_.match_distance) pairs.emplace_back(d, tracks_[t].id, t, o);
        }
    std::sort(pairs.begin(), pairs.end());
    std::vector<bool> track_taken(tracks_.size(), false), object_taken(observations.size(), false);
    std::vector<std::size_t> track_object(tracks_.size(), observations.size());
    for (const auto& [d, id, t, o] : pairs) {
        if (track_taken[t] || object_taken[o]) continue;
        track_taken[t] = object_taken[o] = true;
        track_object[t] = o;
    }

    const double log_floor = std::log(options_.evidence_floor);
    auto observe = [&](std::size_t t, const TrackedObservation& obs) {
        ObjectTrack& track = tracks_[t];
        track.position = obs.position;
        ++track.frames;
        track.misses = 0;
        track.last_frame = frames_;
        if (obs.evidence.empty()) return;
        ++track.evidence_frames;
        for (const ClassEvidence& e : obs.evidence) {
            const double gain =
                std::log(std::max(e.probability, options_.evidence_floor)) - log_floor;
            auto& sums = excess_[t];
            auto it = std::find_if(sums.begin(), sums.end(),
                                   [&](const auto& s) { return s.first == e.class_name; });
            if (it == sums.end())
                sums.emplace_back(e.class_name, gain);
            else
                it->second += gain;
        }
        track.classes = fuse(excess_[t], track.evidence_frames, options_.evidence_floor);
    };

    // Seen tracks are updated, missed ones age and end past max_misses.
    std::vector<ObjectTrack> kept;
    std::vector<std::vector<std::pair<std::string, double>>> kept_excess;
    for (std::size_t t = 0; t < tracks_.size(); ++t) {
        if (track_object[t] < observations.size()) {
            observe(t, observations[track_object[t]]);
            result.object_track[track_object[t]] = tracks_[t].id;
        } else if (++tracks_[t].misses > static_cast<std::size_t>(options_.max_misses)) {
            result.ended.push_back(tracks_[t]);
            continue;
        }
        kept.push_back(std::move(tracks_[t]));
        kept_excess.push_back(std::move(excess_[t]));
    }
    tracks_ = std::move(kept);
    excess_ = std::move(kept_excess);

    // New tracks for the objects no track took, in the objects' order.
    for (std::size_t o = 0; o < observations.size(); ++o) {
        if (object_taken[o]) continue;
        ObjectTrack track;
        track.id = next_id_++;
        track.first_frame = frames_;
        tracks_.push_back(track);
        excess_.emplace_back();
        observe(tracks_.size() - 1, observations[o]);
        result.object_track[o] = track.id;
        result.born.push_back(track.id);
    }
    ++frames_;
    return result;
}

}  // namespace esf
