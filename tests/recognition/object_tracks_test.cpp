// Tracks over hand-made frame sequences: association by position, birth, misses and end, and
// the fused class.

#include "esf/recognition/object_tracks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "../support/error_of.hpp"

namespace {

using esf::ClassEvidence;
using esf::TrackedObservation;

TrackedObservation at(float x, float y, std::vector<ClassEvidence> evidence = {}) {
    TrackedObservation o;
    o.position = Eigen::Vector3f(x, y, 1.0f);
    o.evidence = std::move(evidence);
    return o;
}

std::vector<ClassEvidence> says(const std::string& name, double p = 0.8) {
    return {{name, p}, {"other", 1.0 - p}};
}

TEST(ClassEvidence, HalfNearestHalfVotes) {
    esf::Classification c;
    for (const char* name : {"mug", "bowl", "mug", "can"}) {
        esf::NeighbourView n;
        n.class_name = name;
        c.neighbours.push_back(n);
    }
    const auto e = esf::class_evidence(c);
    ASSERT_EQ(e.size(), 3u);
    EXPECT_EQ(e[0].class_name, "mug");  // 0.5 + 0.5 * 2/4
    EXPECT_DOUBLE_EQ(e[0].probability, 0.75);
    EXPECT_EQ(e[1].class_name, "bowl");  // 0.5 * 1/4, ties by name
    EXPECT_DOUBLE_EQ(e[1].probability, 0.125);
    EXPECT_EQ(e[2].class_name, "can");
    EXPECT_TRUE(esf::class_evidence(esf::Classification{}).empty());
}

TEST(ObjectTracker, SamePlaceSameTrack) {
    esf::ObjectTracker tracker;
    // Frame 0: two objects 20 cm apart; frame 1: both moved 2 cm (within 5 cm), listed the
    // other way round.
    const std::vector<TrackedObservation> f0 = {at(0.0f, 0.0f), at(0.2f, 0.0f)};
    const std::vector<TrackedObservation> f1 = {at(0.22f, 0.0f), at(0.0f, 0.02f)};
    auto u0 = tracker.update(f0);
    EXPECT_EQ(u0.object_track, (std::vector<std::uint64_t>{1, 2}));
    EXPECT_EQ(u0.born, (std::vector<std::uint64_t>{1, 2}));
    auto u1 = tracker.update(f1);
    EXPECT_EQ(u1.object_track, (std::vector<std::uint64_t>{2, 1}));
    EXPECT_TRUE(u1.born.empty());
    ASSERT_EQ(tracker.tracks().size(), 2u);
    EXPECT_EQ(tracker.tracks()[0].frames, 2u);
    EXPECT_FLOAT_EQ(tracker.tracks()[0].position.y(), 0.02f);  // the last object's position
    EXPECT_FLOAT_EQ(tracker.tracks()[1].position.x(), 0.22f);
}

TEST(ObjectTracker, FartherThanTheToleranceIsANewObject) {
    esf::ObjectTracker tracker;  // 5 cm
    tracker.update(std::vector<TrackedObservation>{at(0.0f, 0.0f)});
    auto u = tracker.update(std::vector<TrackedObservation>{at(0.06f, 0.0f)});
    EXPECT_EQ(u.object_track, (std::vector<std::uint64_t>{2}));
    EXPECT_EQ(tracker.tracks().size(), 2u);
    EXPECT_EQ(tracker.tracks()[0].misses, 1u);
}

TEST(ObjectTracker, NearestPairsFirst) {
    esf::ObjectTracker tracker;
    tracker.update(std::vector<TrackedObservation>{at(0.0f, 0.0f), at(0.06f, 0.0f)});
    // The object at 3 cm is 3 cm from both tracks; the one at 5.5 cm is 0.5 cm from track 2, so
    // track 2 takes it and track 1 takes the other.
    auto u = tracker.update(std::vector<TrackedObservation>{at(0.03f, 0.0f), at(0.055f, 0.0f)});
    EXPECT_EQ(u.object_track, (std::vector<std::uint64_t>{1, 2}));
}

TEST(ObjectTracker, ShortMissesSurviveLongOnesEnd) {
    esf::TrackingOptions options;
    options.max_misses = 2;
    esf::ObjectTracker tracker(options);
    const std::vector<TrackedObservation> seen = {at(0.0f, 0.0f, says("mug"))}, none;
    tracker.update(seen);
    tracker.update(none);  // miss 1
    tracker.update(none);  // miss 2
    auto back = tracker.update(seen);
    EXPECT_EQ(back.object_track, (std::vector<std::uint64_t>{1}));  // survived
    EXPECT_EQ(tracker.tracks()[0].frames, 2u);
    tracker.update(none);
    tracker.update(none);
    auto end = tracker.update(none);  // miss 3 > 2
    ASSERT_EQ(end.ended.size(), 1u);
    EXPECT_EQ(end.ended[0].id, 1u);
    EXPECT_EQ(end.ended[0].class_name(), "mug");
    EXPECT_EQ(end.ended[0].last_frame, 3u);
    EXPECT_TRUE(tracker.tracks().empty());
    auto reborn = tracker.update(seen);
    EXPECT_EQ(reborn.born, (std::vector<std::uint64_t>{2}));  // ids are never reused
    EXPECT_EQ(tracker.tracks_started(), 2u);
}

TEST(ObjectTracker, FusesLogLikelihoodsOverFrames) {
    esf::ObjectTracker tracker;  // floor 0.01
    const std::vector<ClassEvidence> weak_bowl = {{"bowl", 0.6}, {"mug", 0.3}};
    const std::vector<ClassEvidence> sure_mug = {{"mug", 0.9}, {"bowl", 0.05}};
    tracker.update(std::vector<TrackedObservation>{at(0, 0, weak_bowl)});
    EXPECT_EQ(tracker.tracks()[0].class_name(), "bowl");
    EXPECT_NEAR(tracker.tracks()[0].confidence(), 0.6 / 0.9, 1e-12);
    // bowl: log 0.6 + log 0.05 = -3.51, mug: log 0.3 + log 0.9 = -1.31.
    tracker.update(std::vector<TrackedObservation>{at(0, 0, sure_mug)});
    EXPECT_EQ(tracker.tracks()[0].class_name(), "mug");
    // A third frame like the first: bowl named first in two frames of three, but the product
    // still favours mug (0.3 x 0.9 x 0.3 against 0.6 x 0.05 x 0.6).
    tracker.update(std::vector<TrackedObservation>{at(0, 0, weak_bowl)});
    const esf::ObjectTrack& t = tracker.tracks()[0];
    ASSERT_EQ(t.classes.size(), 2u);
    EXPECT_EQ(t.classes[0].class_name, "mug");
    EXPECT_NEAR(t.classes[0].log_likelihood, 2 * std::log(0.3) + std::log(0.9), 1e-12);
    EXPECT_EQ(t.classes[1].class_name, "bowl");
    EXPECT_NEAR(t.classes[1].log_likelihood, 2 * std::log(0.6) + std::log(0.05), 1e-12);
    EXPECT_NEAR(t.classes[0].confidence, 0.081 / (0.081 + 0.018), 1e-12);
    EXPECT_NEAR(t.classes[0].confidence + t.classes[1].confidence, 1.0, 1e-12);
    EXPECT_EQ(t.evidence_frames, 3u);

    // A class a frame does not name gets the floor there.
    tracker.update(std::vector<TrackedObservation>{at(0, 0, {{"can", 1.0}})});
    EXPECT_NEAR(tracker.tracks()[0].classes.back().log_likelihood, 3 * std::log(0.01), 1e-12);
}

TEST(ObjectTracker, ObjectsWithoutClassAreSeenWithoutEvidence) {
    esf::ObjectTracker tracker;
    tracker.update(std::vector<TrackedObservation>{at(0, 0)});
    EXPECT_FALSE(tracker.tracks()[0].has_class());
    EXPECT_EQ(tracker.tracks()[0].class_name(), "");
    EXPECT_EQ(tracker.tracks()[0].confidence(), 0.0);
    tracker.update(std::vector<TrackedObservation>{at(0, 0, says("can", 1.0))});
    EXPECT_EQ(tracker.tracks()[0].frames, 2u);
    EXPECT_EQ(tracker.tracks()[0].evidence_frames, 1u);
    EXPECT_EQ(tracker.tracks()[0].class_name(), "can");
}

TEST(ObjectTracker, SceneObservationsDropCentroidsOntoThePlane) {
    esf::SceneRecognition scene;
    scene.plane_found = true;
    scene.plane.normal = Eigen::Vector3f(0, -1, 0);  // y down in the camera: up is -y
    scene.plane.d = 0.5f;                            // the table at y = 0.5
    esf::RecognizedObject o;
    o.cluster.centroid = Eigen::Vector3f(0.1f, 0.4f, 1.0f);  // 10 cm above the table
    o.error = "too few points";
    scene.objects.push_back(o);
    const auto obs = esf::scene_observations(scene);
    ASSERT_EQ(obs.size(), 1u);
    EXPECT_TRUE(obs[0].position.isApprox(Eigen::Vector3f(0.1f, 0.5f, 1.0f)));
    EXPECT_TRUE(obs[0].evidence.empty());
}

TEST(ObjectTracker, BadOptionsAndPositionsAreRefused) {
    esf::TrackingOptions o;
    o.match_distance = 0.0;
    EXPECT_CONTAINS(esf::test::error_of([&] { esf::ObjectTracker t(o); }), "match distance");
    o = {};
    o.max_misses = -1;
    EXPECT_CONTAINS(esf::test::error_of([&] { esf::ObjectTracker t(o); }), "max misses");
    o = {};
    o.evidence_floor = 1.0;
    EXPECT_CONTAINS(esf::test::error_of([&] { esf::ObjectTracker t(o); }), "evidence floor");
    esf::ObjectTracker tracker;
    EXPECT_CONTAINS(
        esf::test::error_of([&] { tracker.update(std::vector<TrackedObservation>{at(NAN, 0)}); }),
        "tracked object 0 has a non-finite position");
}

}  // namespace
