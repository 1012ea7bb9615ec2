// Tracks over hand-made frame sequences: association by position, birth, misses and end, and
// the fused class under every rule (the frames' votes, nearest models, class likelihoods), with
// hand-computed numbers.

#include "esf/recognition/object_tracks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "../support/error_of.hpp"

namespace {

using esf::ClassEvidence;
using esf::ModelEvidence;
using esf::TrackedObservation;

TrackedObservation at(float x, float y, std::vector<ClassEvidence> evidence = {},
                      std::vector<ModelEvidence> models = {}) {
    TrackedObservation o;
    o.position = Eigen::Vector3f(x, y, 1.0f);
    o.evidence = std::move(evidence);
    o.models = std::move(models);
    return o;
}

std::vector<ClassEvidence> says(const std::string& name, double p = 0.8) {
    return {{name, p}, {"other", 1.0 - p}};
}

/// A frame whose nearest model is of class `name` (at 1.0), the next of another class (at 2.0).
std::vector<ModelEvidence> nearest(const std::string& name) {
    return {{name, name + "_1", 1.0}, {"other", "other_1", 2.0}};
}

/// A tracker that fuses by the nearest models (FusionRule::kNearestModels).
esf::TrackingOptions by_models() {
    esf::TrackingOptions o;
    o.fusion = esf::FusionRule::kNearestModels;
    return o;
}

/// A track at the origin for each frame's models, fused by the nearest models.
TrackedObservation models_at_origin(std::vector<ModelEvidence> models) {
    return at(0, 0, {}, std::move(models));
}

esf::NeighbourView neighbour(const std::string& class_name, const std::string& model,
                             double distance) {
    esf::NeighbourView n;
    n.class_name = class_name;
    n.model_name = model;
    n.distance = distance;
    return n;
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

TEST(ObjectTracker, MatchSaysWhichTrackAnUpdateWillGive) {
    esf::ObjectTracker tracker;
    const std::vector<TrackedObservation> first = {at(0.0f, 0.0f), at(0.2f, 0.0f)};
    tracker.update(first);
    ASSERT_EQ(tracker.tracks().size(), 2u);
    // The second object moved nearer the first track's place than the first object did, but
    // pairs go nearest first: each keeps its own; the third is new.
    const std::vector<TrackedObservation> second = {at(0.21f, 0.0f), at(0.01f, 0.0f),
                                                    at(0.5f, 0.0f)};
    std::vector<Eigen::Vector3f> positions;
    for (const TrackedObservation& o : second) positions.push_back(o.position);
    const std::vector<std::size_t> match = tracker.match(positions);
    EXPECT_EQ(match, (std::vector<std::size_t>{1, 0, 2}));
    const std::uint64_t ids[] = {tracker.tracks()[1].id, tracker.tracks()[0].id};
    const esf::TrackUpdate update = tracker.update(second);
    EXPECT_EQ(update.object_track[0], ids[0]);
    EXPECT_EQ(update.object_track[1], ids[1]);
    EXPECT_EQ(update.born, (std::vector<std::uint64_t>{update.object_track[2]}));
}

TEST(ObjectTracker, ATrackKeepsItsLastVerifiedFit) {
    esf::ObjectTracker tracker(by_models());
    TrackedObservation verified = at(0.0f, 0.0f, {}, nearest("mug"));
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
    pose(0, 3) = 0.25f;
    verified.fit = esf::FitEvidence{"mug", "mug_1", 0.8, 3, pose};
    tracker.update(std::vector<TrackedObservation>{verified});
    ASSERT_TRUE(tracker.tracks().front().fit.has_value());
    EXPECT_EQ(tracker.tracks().front().fit->model_id, 3);
    // A later frame without a fit keeps it; one with a fit replaces it.
    tracker.update(std::vector<TrackedObservation>{at(0.0f, 0.0f, {}, nearest("mug"))});
    ASSERT_TRUE(tracker.tracks().front().fit.has_value());
    EXPECT_EQ(tracker.tracks().front().fit->pose, pose);
    verified.fit->model_id = 4;
    tracker.update(std::vector<TrackedObservation>{verified});
    EXPECT_EQ(tracker.tracks().front().fit->model_id, 4);
    // Fits do not vote: the fused class is the nearest models' (here the same frames' "mug").
    EXPECT_EQ(tracker.tracks().front().class_name(), "mug");
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
    esf::TrackingOptions options = by_models();
    options.max_misses = 2;
    esf::ObjectTracker tracker(options);
    const std::vector<TrackedObservation> seen = {at(0.0f, 0.0f, says("mug"), nearest("mug"))},
                                          none;
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
    esf::TrackingOptions options;  // floor 0.01
    options.fusion = esf::FusionRule::kClassLikelihood;
    esf::ObjectTracker tracker(options);
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
    EXPECT_NEAR(t.classes[0].score, 2 * std::log(0.3) + std::log(0.9), 1e-12);
    EXPECT_EQ(t.classes[1].class_name, "bowl");
    EXPECT_NEAR(t.classes[1].score, 2 * std::log(0.6) + std::log(0.05), 1e-12);
    EXPECT_NEAR(t.classes[0].confidence, 0.081 / (0.081 + 0.018), 1e-12);
    EXPECT_NEAR(t.classes[0].confidence + t.classes[1].confidence, 1.0, 1e-12);
    EXPECT_EQ(t.evidence_frames, 3u);

    // A class a frame does not name gets the floor there.
    tracker.update(std::vector<TrackedObservation>{at(0, 0, {{"can", 1.0}})});
    EXPECT_NEAR(tracker.tracks()[0].classes.back().score, 3 * std::log(0.01), 1e-12);
    EXPECT_TRUE(tracker.tracks()[0].classes.back().model.empty());

    // This rule reads the class evidence only: models alone are a frame without a class.
    tracker.update(std::vector<TrackedObservation>{models_at_origin(nearest("can"))});
    EXPECT_EQ(tracker.tracks()[0].frames, 5u);
    EXPECT_EQ(tracker.tracks()[0].evidence_frames, 4u);
}

TEST(ObjectTracker, ObjectsWithoutClassAreSeenWithoutEvidence) {
    esf::ObjectTracker tracker(by_models());
    tracker.update(std::vector<TrackedObservation>{at(0, 0)});
    EXPECT_FALSE(tracker.tracks()[0].has_class());
    EXPECT_EQ(tracker.tracks()[0].class_name(), "");
    EXPECT_EQ(tracker.tracks()[0].confidence(), 0.0);
    // Class evidence alone is no evidence for this rule.
    tracker.update(std::vector<TrackedObservation>{at(0, 0, says("can", 1.0))});
    EXPECT_FALSE(tracker.tracks()[0].has_class());
    tracker.update(std::vector<TrackedObservation>{at(0, 0, says("can", 1.0), nearest("can"))});
    EXPECT_EQ(tracker.tracks()[0].frames, 3u);
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
    EXPECT_TRUE(obs[0].models.empty());

    // A classified object carries both rules' evidence.
    o.error.clear();
    o.classification.neighbours = {neighbour("mug", "m1", 1.0), neighbour("mug", "m1", 1.5),
                                   neighbour("bowl", "b1", 2.0)};
    scene.objects = {o};
    const auto classified = esf::scene_observations(scene);
    ASSERT_EQ(classified[0].models.size(), 2u);
    EXPECT_EQ(classified[0].models[1].model_name, "b1");
    ASSERT_EQ(classified[0].evidence.size(), 2u);
    EXPECT_DOUBLE_EQ(classified[0].evidence[0].probability, 0.5 + 0.5 * 2.0 / 3.0);
}

TEST(ModelEvidence, DistinctModelsNearestFirst) {
    esf::Classification c;
    // Every view voting (several views of m1), a verified order (not nearest first), and one
    // model name in two classes (two models).
    c.neighbours = {neighbour("bowl", "b1", 1.5), neighbour("mug", "m1", 1.0),
                    neighbour("mug", "m1", 0.9),  neighbour("mug", "m2", 1.3),
                    neighbour("box", "x", 2.0),   neighbour("can", "x", 2.0)};
    const auto m = esf::model_evidence(c);
    ASSERT_EQ(m.size(), 5u);
    EXPECT_EQ(m[0].model_name, "m1");
    EXPECT_DOUBLE_EQ(m[0].distance, 0.9);  // its nearest view
    EXPECT_EQ(m[1].model_name, "m2");
    EXPECT_EQ(m[2].model_name, "b1");
    EXPECT_EQ(m[3].class_name, "box");  // equal distances keep the neighbours' order
    EXPECT_EQ(m[4].class_name, "can");
    EXPECT_TRUE(esf::model_evidence(esf::Classification{}).empty());
}

TEST(ModelScores, MarginTimesNearnessToTheKth) {
    // d_1 = 1, nearest other class (bowl) at 2, k-th at 4: w = 1 - 1/2 = 0.5.
    const std::vector<ModelEvidence> frame = {
        {"mug", "m1", 1.0}, {"mug", "m2", 1.5}, {"bowl", "b1", 2.0}, {"can", "c1", 4.0}};
    const auto s = esf::model_scores(frame);
    ASSERT_EQ(s.size(), 4u);
    EXPECT_EQ(s[0].model_name, "m1");
    EXPECT_DOUBLE_EQ(s[0].score, 0.5 * (1.0 - 1.0 / 4.0));  // 0.375
    EXPECT_DOUBLE_EQ(s[1].score, 0.5 * (1.0 - 1.5 / 4.0));  // 0.3125
    EXPECT_DOUBLE_EQ(s[2].score, 0.5 * (1.0 - 2.0 / 4.0));  // 0.25
    EXPECT_DOUBLE_EQ(s[3].score, 0.0);                      // the k-th
    EXPECT_EQ(s[2].class_name, "bowl");

    // All of one class: the other class is taken at the k-th distance (w = 1 - 1/2).
    const auto one_class = esf::model_scores(
        std::vector<ModelEvidence>{{"mug", "m1", 1.0}, {"mug", "m2", 1.2}, {"mug", "m3", 2.0}});
    EXPECT_DOUBLE_EQ(one_class[0].score, 0.5 * 0.5);
    EXPECT_DOUBLE_EQ(one_class[1].score, 0.5 * 0.4);
    // Two classes at the nearest distance: no margin, the frame earns nothing.
    const auto torn = esf::model_scores(
        std::vector<ModelEvidence>{{"mug", "m1", 1.0}, {"bowl", "b1", 1.0}, {"can", "c1", 2.0}});
    EXPECT_DOUBLE_EQ(torn[0].score, 0.0);
    EXPECT_DOUBLE_EQ(torn[1].score, 0.0);
    // One distance for all (k = 1, or ties): a plain vote for the nearest.
    const auto single = esf::model_scores(std::vector<ModelEvidence>{{"mug", "m1", 0.7}});
    ASSERT_EQ(single.size(), 1u);
    EXPECT_DOUBLE_EQ(single[0].score, 1.0);
    const auto tied =
        esf::model_scores(std::vector<ModelEvidence>{{"mug", "m1", 0.0}, {"bowl", "b1", 0.0}});
    EXPECT_DOUBLE_EQ(tied[0].score, 1.0);
    EXPECT_DOUBLE_EQ(tied[1].score, 0.0);
    EXPECT_TRUE(esf::model_scores({}).empty());
}

TEST(ModelScores, BadDistancesAreRefused) {
    EXPECT_CONTAINS(
        esf::test::error_of([] {
            esf::model_scores(std::vector<ModelEvidence>{{"mug", "m1", 1.0}, {"bowl", "b1", 0.5}});
        }),
        "models must come nearest first, but model 1 ('b1')");
    EXPECT_CONTAINS(esf::test::error_of([] {
                        esf::model_scores(std::vector<ModelEvidence>{{"mug", "m1", -1.0}});
                    }),
                    "model 0 ('m1') has a negative or non-finite distance");
    EXPECT_CONTAINS(
        esf::test::error_of([] {
            esf::model_scores(std::vector<ModelEvidence>{{"mug", "m1", 1.0}, {"mug", "m2", NAN}});
        }),
        "model 1 ('m2') has a negative or non-finite distance");
}

TEST(ObjectTracker, FusesNearestModelsOverFrames) {
    esf::ObjectTracker tracker(by_models());
    // Torn between bowl and mug: w = 1 - 1/1.1 = 1/11; b1 earns w (1 - 1/2) = 1/22, m1 earns
    // w (1 - 1.1/2) = 9/220, c1 (the k-th) nothing.
    const std::vector<ModelEvidence> torn_bowl = {
        {"bowl", "b1", 1.0}, {"mug", "m1", 1.1}, {"can", "c1", 2.0}};
    // Sure of mug: w = 1 - 1/4 = 3/4; m1 earns 3/4 x 3/4 = 0.5625, m2 3/4 x 5/8 = 0.46875.
    const std::vector<ModelEvidence> sure_mug = {
        {"mug", "m1", 1.0}, {"mug", "m2", 1.5}, {"bowl", "b1", 4.0}};
    tracker.update(std::vector<TrackedObservation>{models_at_origin(torn_bowl)});
    {
        const esf::ObjectTrack& t = tracker.tracks()[0];
        ASSERT_EQ(t.classes.size(), 3u);
        EXPECT_EQ(t.class_name(), "bowl");  // one frame: its nearest model's class
        EXPECT_NEAR(t.classes[0].score, 1.0 / 22.0, 1e-12);
        EXPECT_NEAR(t.confidence(), (10.0 / 220.0) / (19.0 / 220.0), 1e-12);  // 10/19
        EXPECT_EQ(t.classes[2].class_name, "can");
        EXPECT_EQ(t.classes[2].score, 0.0);
    }
    tracker.update(std::vector<TrackedObservation>{models_at_origin(sure_mug)});
    tracker.update(std::vector<TrackedObservation>{models_at_origin(torn_bowl)});
    tracker.update(std::vector<TrackedObservation>{models_at_origin(torn_bowl)});
    // bowl's model was nearest in three frames of four, but the one sure frame outweighs them:
    // m1 = 3 x 9/220 + 0.5625, b1 = 3/22.
    const esf::ObjectTrack& t = tracker.tracks()[0];
    EXPECT_EQ(t.evidence_frames, 4u);
    ASSERT_EQ(t.classes.size(), 3u);
    const double m1 = 27.0 / 220.0 + 0.5625, b1 = 3.0 / 22.0;
    EXPECT_EQ(t.classes[0].class_name, "mug");
    EXPECT_EQ(t.classes[0].model, "m1");
    EXPECT_NEAR(t.classes[0].score, m1, 1e-12);  // its best model, not the sum with m2
    EXPECT_EQ(t.classes[0].nearest, 1u);
    EXPECT_EQ(t.classes[1].class_name, "bowl");
    EXPECT_NEAR(t.classes[1].score, b1, 1e-12);
    EXPECT_EQ(t.classes[1].nearest, 3u);
    EXPECT_NEAR(t.confidence(), m1 / (m1 + b1), 1e-12);
    EXPECT_NEAR(t.classes[0].confidence + t.classes[1].confidence + t.classes[2].confidence, 1.0,
                1e-12);
}

TEST(ObjectTracker, NearestModelTiesGoToTheNearestFrames) {
    esf::ObjectTracker tracker(by_models());
    // Two classes at the nearest distance: every score is 0; mug's model was the nearest (first)
    // once, so mug comes before bowl (which the name would put first), and the confidences are
    // the shares of the nearest frames.
    tracker.update(std::vector<TrackedObservation>{
        models_at_origin({{"mug", "m1", 1.0}, {"bowl", "b1", 1.0}, {"can", "c1", 2.0}})});
    const esf::ObjectTrack& t = tracker.tracks()[0];
    EXPECT_EQ(t.class_name(), "mug");
    EXPECT_DOUBLE_EQ(t.confidence(), 1.0);
    EXPECT_EQ(t.classes[1].class_name, "bowl");
    EXPECT_DOUBLE_EQ(t.classes[1].confidence, 0.0);
}

/// A frame that named `name` with these models.
TrackedObservation named(const std::string& name, std::vector<ModelEvidence> models) {
    TrackedObservation o = at(0, 0, {}, std::move(models));
    o.class_name = name;
    return o;
}

TEST(ObjectTracker, FusesTheFramesClassesByVote) {
    esf::ObjectTracker tracker;  // frame votes, the default
    // The sure mug frame would outweigh three torn bowl frames by the models' earnings (above);
    // by votes the three frames that named bowl win, 3 to 1.
    const std::vector<ModelEvidence> torn_bowl = {
        {"bowl", "b1", 1.0}, {"mug", "m1", 1.1}, {"can", "c1", 2.0}};
    const std::vector<ModelEvidence> sure_mug = {
        {"mug", "m1", 1.0}, {"mug", "m2", 1.5}, {"bowl", "b1", 4.0}};
    tracker.update(std::vector<TrackedObservation>{named("mug", sure_mug)});
    EXPECT_EQ(tracker.tracks()[0].class_name(), "mug");
    EXPECT_EQ(tracker.tracks()[0].classes[0].model, "m1");
    for (int i = 0; i < 3; ++i)
        tracker.update(std::vector<TrackedObservation>{named("bowl", torn_bowl)});
    const esf::ObjectTrack& t = tracker.tracks()[0];
    EXPECT_EQ(t.evidence_frames, 4u);
    ASSERT_EQ(t.classes.size(), 2u);  // the classes frames named
    EXPECT_EQ(t.class_name(), "bowl");
    EXPECT_EQ(t.classes[0].score, 3.0);
    EXPECT_DOUBLE_EQ(t.confidence(), 0.75);
    EXPECT_EQ(t.classes[0].model, "b1");
    EXPECT_EQ(t.classes[0].nearest, 3u);
    EXPECT_EQ(t.classes[1].class_name, "mug");
    EXPECT_DOUBLE_EQ(t.classes[1].confidence, 0.25);
    // A frame that named the class verification chose, though its nearest model is a can's.
    tracker.update(std::vector<TrackedObservation>{named("mug", nearest("can"))});
    EXPECT_EQ(tracker.tracks()[0].classes[1].score, 2.0);
}

TEST(ObjectTracker, TiedVotesGoToTheLargerEarnings) {
    esf::ObjectTracker tracker;
    // One vote each; mug's model earned more (a sure frame), so mug comes first though the
    // bowl frame came first and "bowl" comes first by name.
    tracker.update(std::vector<TrackedObservation>{
        named("bowl", {{"bowl", "b1", 1.0}, {"mug", "m1", 1.1}, {"can", "c1", 2.0}})});
    tracker.update(std::vector<TrackedObservation>{
        named("mug", {{"mug", "m1", 1.0}, {"mug", "m2", 1.5}, {"bowl", "b1", 4.0}})});
    const esf::ObjectTrack& t = tracker.tracks()[0];
    EXPECT_EQ(t.class_name(), "mug");
    EXPECT_DOUBLE_EQ(t.confidence(), 0.5);
    // A frame without a class is seen without a vote.
    tracker.update(std::vector<TrackedObservation>{at(0, 0)});
    EXPECT_EQ(tracker.tracks()[0].frames, 3u);
    EXPECT_EQ(tracker.tracks()[0].evidence_frames, 2u);
    EXPECT_EQ(tracker.tracks()[0].class_name(), "mug");
}

TEST(ObjectTracker, ARefusedFrameLeavesNoTrace) {
    esf::ObjectTracker tracker;
    tracker.update(std::vector<TrackedObservation>{models_at_origin(nearest("mug"))});
    const std::vector<TrackedObservation> bad = {
        at(0.3f, 0, {}, nearest("can")), at(0, 0, {}, {{"mug", "m1", 2.0}, {"bowl", "b1", 1.0}})};
    EXPECT_CONTAINS(esf::test::error_of([&] { tracker.update(bad); }),
                    "tracked object 1: models must come nearest first");
    EXPECT_EQ(tracker.frames(), 1u);
    ASSERT_EQ(tracker.tracks().size(), 1u);
    EXPECT_EQ(tracker.tracks()[0].frames, 1u);
    EXPECT_EQ(tracker.tracks_started(), 1u);
}

TEST(FusionRule, Names) {
    EXPECT_STREQ(esf::to_string(esf::FusionRule::kNearestModels), "models");
    EXPECT_EQ(esf::parse_enum<esf::FusionRule>("frames"), esf::FusionRule::kFrameVotes);
    EXPECT_EQ(esf::parse_enum<esf::FusionRule>("likelihood"), esf::FusionRule::kClassLikelihood);
    EXPECT_CONTAINS(esf::test::error_of([] { esf::parse_enum<esf::FusionRule>("votes"); }),
                    "fusion rule");
    EXPECT_EQ(esf::TrackingOptions{}.fusion, esf::FusionRule::kFrameVotes);
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
