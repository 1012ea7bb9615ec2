// The recognizer on a database of a procedural mug and bowl: its settings, held-out views,
// neighbours against brute-force L1, batches and bad clouds.

#include "esf/recognition/recognizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/mesh/model_surface.hpp"
#include "esf/recognition/knn_index.hpp"
#include "esf/recognition/pose_verification.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"
#include "support/error_of.hpp"
#include "support/recognizer_fixture.hpp"
#include "support/test_meshes.hpp"

namespace fs = std::filesystem;

namespace {

using esf::test::kHeldOut;
using esf::test::kSamples;
using esf::test::kShapes;
using esf::test::RecognizerTest;
using esf::test::temp_dir;

TEST_F(RecognizerTest, LoadsTheDatabaseAndItsSettings) {
    const esf::Recognizer recognizer(db_path_);
    const esf::RecognizerInfo& info = recognizer.info();
    EXPECT_EQ(info.database, db_path_);
    EXPECT_EQ(info.setup.kind, (esf::DescriptorKind{"esf", esf::kEsfVersion, esf::kEsfSize}));
    EXPECT_EQ(info.setup.esf.samples, kSamples);
    EXPECT_EQ(info.setup.esf.seed, 5u);
    EXPECT_EQ(info.setup.esf.grid_size, 64);
    EXPECT_FALSE(info.weighted);
    EXPECT_EQ(info.models, 2u);
    EXPECT_EQ(info.categories, kShapes);
    EXPECT_EQ(info.views, info.rows);
    EXPECT_GE(info.views, 120u);  // 160 rendered, thin edge-on views may be skipped
    EXPECT_EQ(recognizer.classifier().labels().size(), info.views);
}

TEST_F(RecognizerTest, QueryDescriptorUsesTheDatabaseSettings) {
    const esf::Recognizer recognizer(db_path_);
    const esf::Points view = held_out_view("mug", kHeldOut[0], 1);
    esf::EsfOptions options;
    options.samples = kSamples;
    options.seed = 5;
    const esf::EsfResult expected = esf::compute_esf(view, options);
    const esf::QueryDescriptor d = recognizer.describe(view);
    ASSERT_TRUE(d.ok()) << d.error;
    EXPECT_EQ(d.points, view.size());
    ASSERT_EQ(d.signatures.size(), static_cast<std::size_t>(esf::kEsfSize));
    EXPECT_TRUE(std::equal(d.signatures.begin(), d.signatures.end(), expected.descriptor.begin()));
}

TEST_F(RecognizerTest, HeldOutViewsAreClassified) {
    esf::RecognizerOptions knn_only;  // the pose is the nearest view's, not a fitted one
    knn_only.verify = false;
    const esf::Recognizer recognizer(db_path_, knn_only);
    const esf::Database db(db_path_);
    for (const auto& shape : kShapes) {
        for (std::size_t i = 0; i < kHeldOut.size(); ++i) {
            SCOPED_TRACE(shape + " held-out view " + std::to_string(i));
            const esf::Points view = held_out_view(shape, kHeldOut[i], i);
            ASSERT_GT(view.size(), 500u);
            const esf::Classification c = recognizer.classify(view);
            EXPECT_EQ(c.class_name, shape);
            EXPECT_EQ(c.best_model, shape + "_a");
            EXPECT_GE(c.confidence, 0.5);
            EXPECT_LE(c.confidence, 1.0);
            // One neighbour per model by default: fewer than 10 models, all of them.
            ASSERT_EQ(c.neighbours.size(), std::min<std::size_t>(10, recognizer.info().models));
            // The best view is the nearest neighbour of the winning class, with its stored pose.
            const auto nearest = std::find_if(c.neighbours.begin(), c.neighbours.end(),
                                              [&](const auto& n) { return n.class_name == shape; });
            ASSERT_NE(nearest, c.neighbours.end());
            EXPECT_EQ(c.best_view, nearest->view);
            EXPECT_EQ(c.best_distance, nearest->distance);
            for (const esf::ViewEntry& v : db.views(shape, shape + "_a"))
                if (v.index == c.best_view) {
                    EXPECT_TRUE(v.pose.isApprox(c.pose));
                }
            for (std::size_t n = 1; n < c.neighbours.size(); ++n)
                EXPECT_LE(c.neighbours[n - 1].distance, c.neighbours[n].distance);
        }
    }
}

TEST_F(RecognizerTest, VerifiesWithTheStoredSurfacesAndSaysWhenADatabaseHasNone) {
    const esf::Points view = held_out_view("mug", kHeldOut[1], 1);
    const esf::Recognizer stored(db_path_);
    EXPECT_TRUE(stored.verifies());
    EXPECT_EQ(stored.info().verification, "stored surfaces");
    const esf::Classification c = stored.classify(view);
    EXPECT_EQ(c.class_name, "mug");
    ASSERT_TRUE(c.fit.has_value());
    EXPECT_TRUE(c.verified);
    EXPECT_GT(c.fit->inliers, 0.8);
    // The fitted model's camera-facing surface, where the fit placed it, covers the points it
    // was fitted to (some of it faces the camera behind a nearer wall: the converse is weaker).
    const esf::Points posed = stored.posed_surface(c);
    ASSERT_GT(posed.size(), 100u);
    std::size_t near = 0;
    for (const Eigen::Vector3f& q : view) {
        float best = std::numeric_limits<float>::max();
        for (const Eigen::Vector3f& p : posed) best = std::min(best, (p - q).squaredNorm());
        near += best < 0.01f * 0.01f;
    }
    EXPECT_GT(static_cast<double>(near), 0.8 * static_cast<double>(view.size()));

    esf::RecognizerOptions off;
    off.verify = false;
    const esf::Recognizer knn_only(db_path_, off);
    EXPECT_FALSE(knn_only.verifies());
    EXPECT_EQ(knn_only.info().verification, "off");
    const esf::Classification unverified = knn_only.classify(view);
    EXPECT_FALSE(unverified.fit.has_value());
    EXPECT_TRUE(knn_only.posed_surface(unverified).empty());

    // Candidates are fitted nearest first, and a verified fit scoring accept_score ends the
    // search: with -1 the first verified one (here the nearest model) names the object; with 2
    // (the default) every candidate is fitted and the best fit wins.
    esf::RecognizerOptions first_fit, every_fit;
    first_fit.verification.accept_score = -1.0;
    every_fit.verification.accept_score = 2.0;
    const esf::Classification f = esf::Recognizer(db_path_, first_fit).classify(view);
    const esf::Classification e = esf::Recognizer(db_path_, every_fit).classify(view);
    ASSERT_TRUE(f.fit && e.fit);
    ASSERT_TRUE(f.verified);
    EXPECT_EQ(f.best_model, unverified.neighbours.front().model_name);
    EXPECT_GE(e.fit->score(), f.fit->score());

    // A database written without surfaces (as by an earlier esf): k-NN only, and it says why;
    // with the meshes it was trained from, the same fit as the stored surfaces give.
    const fs::path dir = temp_dir();
    const std::string copy = (dir / "copy.sqlite").string();
    {
        const esf::Database from(db_path_);
        esf::Database to(copy, esf::OpenMode::kWrite);
        to.set_settings(from.settings());
        for (const esf::DescriptorKind& kind : from.descriptor_kinds())
            to.add_descriptor_kind(kind);
        for (const esf::ModelInfo& m : from.models()) {
            esf::ModelEntry entry;
            entry.category = m.category;
            entry.name = m.name;
            entry.file = m.file;
            entry.group = m.group;
            entry.scale = m.scale;
            entry.views = from.views(m.category, m.name);
            to.write_model(entry, "esf");
        }
    }
    const esf::Recognizer bare(copy);
    EXPECT_FALSE(bare.verifies());
    EXPECT_NE(bare.info().verification.find("off: 2 of 2 models have no stored surface"),
              std::string::npos)
        << bare.info().verification;
    EXPECT_FALSE(bare.classify(view).fit.has_value());
    esf::RecognizerOptions meshes;
    meshes.verification_meshes = (root_ / "meshes").string();
    const esf::Recognizer resampled(copy, meshes);
    EXPECT_TRUE(resampled.verifies());
    const esf::Classification r = resampled.classify(view);
    EXPECT_EQ(r.best_model, c.best_model);
    ASSERT_TRUE(r.fit.has_value());
    EXPECT_EQ(r.fit->inliers, c.fit->inliers);
    EXPECT_EQ(r.pose, c.pose);
    meshes.verification_meshes = (root_ / "absent").string();
    EXPECT_THROW(esf::Recognizer(copy, meshes), esf::IoError);
    fs::remove_all(dir);
}

TEST_F(RecognizerTest, VerifyListsEveryCandidateItFittedAndChoosesTheBestCompared) {
    // The fixture's two models (two classes, so the look-alike rule does not apply): both are
    // fitted (decide_class), each complete; the one named has the highest score less its shape
    // term, and listing them changes nothing.
    for (const auto& [shape, direction] : {std::pair{std::string("mug"), kHeldOut[0]},
                                           std::pair{std::string("bowl"), kHeldOut[2]}}) {
        const esf::Points view = held_out_view(shape, direction, 1);
        const esf::Recognizer recognizer(db_path_);
        const esf::QueryDescriptor d = recognizer.describe(view);
        ASSERT_TRUE(d.ok()) << d.error;
        const esf::Classification knn = recognizer.classify_descriptor(d.signatures);
        esf::Classification plain = knn, listed = knn;
        recognizer.verify(plain, esf::Observation{view, nullptr});
        std::vector<esf::CandidateFit> candidates;
        recognizer.verify(listed, esf::Observation{view, nullptr}, nullptr, &candidates);
        ASSERT_EQ(candidates.size(), 2u) << shape;
        EXPECT_NE(knn.neighbours[candidates[0].neighbour].model_name,
                  knn.neighbours[candidates[1].neighbour].model_name);
        std::size_t best = 0;
        for (std::size_t j = 0; j < candidates.size(); ++j) {
            EXPECT_FALSE(candidates[j].fit.abandoned);
            EXPECT_GE(candidates[j].shape_term, 0.0);
            const auto compared = [&](std::size_t i) {
                return candidates[i].fit.fit.score() - candidates[i].shape_term;
            };
            if (compared(j) > compared(best)) best = j;
        }
        const esf::NeighbourView& chosen = knn.neighbours[candidates[best].neighbour];
        EXPECT_EQ(listed.best_model, chosen.model_name) << shape;
        EXPECT_EQ(listed.class_name, shape);
        EXPECT_EQ(plain.best_model, listed.best_model);
        ASSERT_TRUE(plain.fit && listed.fit);
        EXPECT_DOUBLE_EQ(plain.fit->score(), listed.fit->score());
        EXPECT_TRUE(plain.pose.isApprox(listed.pose));
    }
}

// Every model's size is free while candidates compete (objects are larger or smaller than the
// models of their class), and the chosen fit of a model of known size is then fitted again at
// that size: a mug 20 % larger than the model (the view scaled about the camera: the same
// image, farther away) is named mug, and its pose is the model's rigid motion, scale 1.
TEST_F(RecognizerTest, EverySizeIsFreeWhileCandidatesCompeteAndThePoseIsMetric) {
    esf::Points view = held_out_view("mug", kHeldOut[1], 1);
    for (Eigen::Vector3f& p : view) p *= 1.2f;
    for (const bool every_size_free : {true, false}) {
        SCOPED_TRACE(every_size_free ? "every size free" : "fixed sizes");
        esf::RecognizerOptions options;
        options.verification.every_size_free = every_size_free;
        const esf::Classification c = esf::Recognizer(db_path_, options).classify(view);
        EXPECT_EQ(c.class_name, "mug");
        ASSERT_TRUE(c.fit.has_value());
        const Eigen::Matrix3d linear = c.pose.topLeftCorner<3, 3>().cast<double>();
        EXPECT_NEAR((linear.transpose() * linear - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-4);
        EXPECT_NEAR(linear.determinant(), 1.0, 1e-4);
    }
    // What the competition sees: at a free size the model explains more of the larger mug.
    const esf::Recognizer recognizer(db_path_);
    const esf::Classification c = recognizer.classify(view);
    const esf::ModelSurface surface = esf::sample_model_surface(meshes_.at("mug"), 1.0, 2000, 3);
    const esf::Observation seen{view, nullptr};
    const esf::PoseFit fixed = esf::fit_model(surface, c.pose.cast<double>(), seen, {}, false);
    const esf::PoseFit free = esf::fit_model(surface, c.pose.cast<double>(), seen, {}, true);
    EXPECT_GT(free.scale, 1.1);
    EXPECT_GT(free.fit.inliers, fixed.fit.inliers + 0.05);
}

/// Trains the paper's ESF for the meshes of `root`/meshes into `db_path` (seed 5).
void train_esf(const fs::path& root, const std::string& db_path, int level,
               std::size_t occlusions) {
    esf::Database db(db_path, esf::OpenMode::kWrite);
    esf::TrainingOptions options;
    options.descriptor = "esf";
    options.render.level = level;
    options.esf.samples = kSamples;
    options.occlusions = occlusions;
    options.seed = 5;
    esf::train((root / "meshes").string(), db, options);
}

// Look-alike models of one class: a can and the same can a fifth larger. With every size free
// both explain a view of the smaller one about equally; the one that needs no resizing names the
// model and the pose, and the class stays can.
TEST(RecognizerLookAlikes, TheModelThatNeedsTheLeastResizingNamesTheModel) {
    const fs::path root = temp_dir();
    const auto write = [&](const std::string& category, const std::string& name,
                           const esf::Mesh& mesh) {
        fs::create_directories(root / "meshes" / category);
        esf::write_ply_mesh((root / "meshes" / category / (name + ".ply")).string(), mesh);
    };
    const esf::Mesh small = esf::test::standing_cylinder(0.035, 0.11);
    write("can", "small", small);
    write("can", "large", esf::test::standing_cylinder(0.042, 0.132));
    write("box", "carton", esf::test::standing_box(0.09, 0.06, 0.2));
    const std::string db_path = (root / "cans.sqlite").string();
    train_esf(root, db_path, 1, esf::kTrainingOcclusions);
    esf::RenderOptions render;
    render.level = 0;
    render.seed = 99;
    const esf::MeshRenderer renderer(small, render);
    const Eigen::Vector3d centre = renderer.centre() * renderer.scale();
    const esf::Recognizer recognizer(db_path);
    esf::RecognizerOptions unweighted;
    unweighted.verification.resize_weight = 0.0;
    const esf::Recognizer by_score(db_path, unweighted);
    std::size_t large_by_score = 0;
    for (std::size_t i = 0; i < kHeldOut.size(); ++i) {
        SCOPED_TRACE("view " + std::to_string(i));
        const Eigen::Vector3d eye = centre + renderer.camera_distance() * kHeldOut[i].normalized();
        const esf::Points view = renderer.render_pose(esf::look_at(eye, centre), i + 1);
        const esf::Classification c = recognizer.classify(view);
        EXPECT_EQ(c.class_name, "can");
        EXPECT_EQ(c.best_model, "small");
        const esf::Classification s = by_score.classify(view);
        EXPECT_EQ(s.class_name, "can");
        large_by_score += s.best_model == "large";
    }
    // By score alone the larger can wins some views: the rule is what names the smaller one.
    EXPECT_GT(large_by_score, 0u);
    esf::RecognizerOptions bad;
    bad.verification.resize_weight = -1.0;
    EXPECT_THROW(esf::Recognizer(db_path, bad), std::invalid_argument);
    fs::remove_all(root);
}

TEST_F(RecognizerTest, APriorFitIsKeptWhileItFitsAndOtherwiseOneCandidateMore) {
    const esf::Points view = held_out_view("mug", kHeldOut[1], 1);
    esf::RecognizerOptions off;
    off.verify = false;
    const esf::Classification unverified = esf::Recognizer(db_path_, off).classify(view);
    const esf::Recognizer recognizer(db_path_);
    const esf::Observation observation{view, nullptr};
    esf::Classification fresh = unverified;
    recognizer.verify(fresh, observation);
    ASSERT_TRUE(fresh.verified);
    ASSERT_EQ(fresh.class_name, "mug");

    // The same object again, its fit the prior: kept, at the pose it had.
    const esf::PriorFit prior{fresh.best_model_id, fresh.pose, fresh.fit->score()};
    esf::Classification again = unverified;
    recognizer.verify(again, observation, &prior);
    EXPECT_TRUE(again.verified);
    EXPECT_EQ(again.best_model, fresh.best_model);
    EXPECT_LT((again.pose.topRightCorner<3, 1>() - fresh.pose.topRightCorner<3, 1>()).norm(),
              0.002f);
    EXPECT_GE(again.fit->score(), fresh.fit->score() - 0.05);

    // The bowl from the mug's pose does not fit as the mug did: the candidates are fitted too
    // and the mug wins as without a prior.
    const auto bowl =
        std::find_if(unverified.neighbours.begin(), unverified.neighbours.end(),
                     [](const esf::NeighbourView& n) { return n.class_name == "bowl"; });
    ASSERT_NE(bowl, unverified.neighbours.end());
    const esf::PriorFit wrong{bowl->model_id, fresh.pose, fresh.fit->score()};
    esf::Classification corrected = unverified;
    recognizer.verify(corrected, observation, &wrong);
    EXPECT_EQ(corrected.class_name, "mug");
    EXPECT_EQ(corrected.best_model, fresh.best_model);

    // A model that is not among the neighbours (none has id 99) is no prior.
    const esf::PriorFit absent{99, fresh.pose, 1.0};
    esf::Classification ignored = unverified;
    recognizer.verify(ignored, observation, &absent);
    EXPECT_EQ(ignored.best_model, fresh.best_model);
    EXPECT_EQ(ignored.pose, fresh.pose);
    EXPECT_EQ(ignored.fit->score(), fresh.fit->score());

    // A scene's priors come one per cluster, or not at all.
    const std::vector<std::optional<esf::PriorFit>> one_prior(1);
    EXPECT_THROW(recognizer.recognize(esf::SegmentationResult{}, esf::PointCloud{}, one_prior),
                 std::invalid_argument);
}

TEST_F(RecognizerTest, OneNearestNeighbourIsTheNearestViewsClass) {
    esf::RecognizerOptions options;
    options.k = 1;
    const esf::Recognizer one(db_path_, options);
    const esf::Recognizer ten(db_path_);
    for (const auto& shape : kShapes) {
        const esf::Points view = held_out_view(shape, kHeldOut[1], 7);
        const esf::Classification c1 = one.classify(view);
        const esf::Classification c10 = ten.classify(view);
        ASSERT_EQ(c1.neighbours.size(), 1u);
        EXPECT_EQ(c1.class_name, c10.neighbours[0].class_name);
        EXPECT_EQ(c1.best_view, c10.neighbours[0].view);
        EXPECT_EQ(c1.confidence, 1.0);
    }
}

struct BruteForceRow {
    double distance;
    std::size_t row;
};

/// Every view at the (weighted) L1 distance of its nearest row to `query` (that row), nearest
/// first, ties by row; `per_model`: only the nearest view of each model.
std::vector<BruteForceRow> brute_force(const esf::DescriptorMatrix& m, std::span<const float> query,
                                       const std::vector<float>& weights, bool per_model = false) {
    std::vector<BruteForceRow> out;
    for (std::size_t r = 0; r < m.rows(); ++r) {
        const auto row = m.row(r);
        double d = 0.0;
        for (std::size_t i = 0; i < row.size(); ++i)
            d += (weights.empty() ? 1.0 : weights[i]) * std::abs(double(row[i]) - query[i]);
        out.push_back({d, r});
    }
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
        return a.distance != b.distance ? a.distance < b.distance : a.row < b.row;
    });
    std::set<std::pair<std::uint32_t, int>> seen;  // (model, view): its nearest row only
    std::erase_if(out, [&](const BruteForceRow& r) {
        return !seen.emplace(m.row_info[r.row].model, m.row_info[r.row].view_index).second;
    });
    if (per_model) {
        std::set<std::uint32_t> models;
        std::erase_if(out, [&](const BruteForceRow& r) {
            return !models.insert(m.row_info[r.row].model).second;
        });
    }
    return out;
}

TEST_F(RecognizerTest, ViewsWithOccludedCopiesAreAsNearAsTheirNearestSignature) {
    const fs::path dir = temp_dir();
    const std::string path = (dir / "occluded.sqlite").string();
    train_esf(root_, path, 0, 2);
    const esf::DescriptorMatrix m = esf::Database(path).load_descriptors();
    for (const bool per_model : {false, true}) {
        esf::RecognizerOptions options;
        options.one_view_per_model = per_model;
        options.k = 5;
        const esf::Recognizer recognizer(path, options);
        EXPECT_GT(recognizer.info().rows, recognizer.info().views);  // the copies
        for (const auto& shape : kShapes) {
            const esf::QueryDescriptor q =
                recognizer.describe(held_out_view(shape, kHeldOut[1], 4));
            ASSERT_TRUE(q.ok());
            const esf::Classification c = recognizer.classify_descriptor(q.signatures);
            const std::vector<BruteForceRow> expected = brute_force(m, q.signatures, {}, per_model);
            ASSERT_EQ(c.neighbours.size(), std::min<std::size_t>(5, expected.size()));
            for (std::size_t n = 0; n < c.neighbours.size(); ++n) {
                const esf::DescriptorRow& row = m.row_info[expected[n].row];
                EXPECT_EQ(c.neighbours[n].model_name, m.models[row.model].name) << n;
                EXPECT_EQ(c.neighbours[n].view, row.view_index) << n;
                EXPECT_NEAR(c.neighbours[n].distance, expected[n].distance,
                            1e-9 * expected[n].distance)
                    << n;
            }
        }
    }
    fs::remove_all(dir);
}

TEST_F(RecognizerTest, NeighboursEqualBruteForceL1) {
    const esf::DescriptorMatrix m = esf::Database(db_path_).load_descriptors();
    // Unweighted, then with learned block weights stored in a copy of the database.
    const fs::path dir = temp_dir();
    const std::string weighted_path = (dir / "weighted.sqlite").string();
    fs::copy_file(db_path_, weighted_path);
    const std::vector<float> blocks = {1.0f, 0.5f,  2.0f, 0.1f, 1.5f,
                                       1.0f, 0.25f, 3.0f, 1.0f, 0.75f};
    esf::Database(weighted_path, esf::OpenMode::kWrite).set_weights(blocks);

    for (const bool weighted : {false, true})
        for (const bool per_model : {false, true}) {
            SCOPED_TRACE(weighted ? "weighted" : "unweighted");
            SCOPED_TRACE(per_model ? "one view per model" : "every view");
            esf::RecognizerOptions options;
            options.one_view_per_model = per_model;
            const esf::Recognizer recognizer(weighted ? weighted_path : db_path_, options);
            EXPECT_EQ(recognizer.info().weighted, weighted);
            std::vector<float> weights;
            if (weighted)
                for (const float w : blocks) weights.insert(weights.end(), esf::kEsfBins, w);
            for (const auto& shape : kShapes) {
                const esf::Points view = held_out_view(shape, kHeldOut[2], 3);
                const esf::QueryDescriptor q = recognizer.describe(view);
                ASSERT_TRUE(q.ok());
                const esf::Classification c = recognizer.classify_descriptor(q.signatures);
                const std::vector<BruteForceRow> expected =
                    brute_force(m, q.signatures, weights, per_model);
                ASSERT_EQ(c.neighbours.size(), std::min<std::size_t>(10, expected.size()));
                for (std::size_t n = 0; n < c.neighbours.size(); ++n) {
                    const esf::DescriptorRow& row = m.row_info[expected[n].row];
                    EXPECT_EQ(c.neighbours[n].class_name, m.categories[row.category]) << n;
                    EXPECT_EQ(c.neighbours[n].model_name, m.models[row.model].name) << n;
                    EXPECT_EQ(c.neighbours[n].view, row.view_index) << n;
                    EXPECT_NEAR(c.neighbours[n].distance, expected[n].distance,
                                1e-9 * expected[n].distance)
                        << n;
                    EXPECT_TRUE(c.neighbours[n].pose.isApprox(row.pose)) << n;
                }
            }
        }
    fs::remove_all(dir);
}

TEST_F(RecognizerTest, BatchEqualsOneByOneForAnyThreadCount) {
    std::vector<esf::Points> clouds;
    for (const auto& shape : kShapes)
        for (std::size_t i = 0; i < 2; ++i) clouds.push_back(held_out_view(shape, kHeldOut[i], i));
    clouds.push_back({{0, 0, 1}, {0, 0, 1.1f}});  // cannot be described
    for (const int threads : {1, 2}) {
        esf::RecognizerOptions options;
        options.threads = threads;
        const esf::Recognizer recognizer(db_path_, options);
        const std::vector<esf::CloudClassification> batch = recognizer.classify_batch(clouds);
        ASSERT_EQ(batch.size(), clouds.size());
        for (std::size_t i = 0; i + 1 < clouds.size(); ++i) {
            ASSERT_TRUE(batch[i].ok()) << batch[i].error;
            const esf::Classification one = recognizer.classify(clouds[i]);
            EXPECT_EQ(batch[i].classification.class_name, one.class_name);
            ASSERT_EQ(batch[i].classification.neighbours.size(), one.neighbours.size());
            for (std::size_t n = 0; n < one.neighbours.size(); ++n) {
                EXPECT_EQ(batch[i].classification.neighbours[n].index, one.neighbours[n].index);
                EXPECT_EQ(batch[i].classification.neighbours[n].distance,
                          one.neighbours[n].distance);
            }
        }
        EXPECT_FALSE(batch.back().ok());
        EXPECT_CONTAINS(batch.back().error, "esf: needs at least 3 finite points");
    }
}

// Every kernel set the CPU runs describes and searches alike: the same descriptor, the same
// neighbours at the same distances, the same verified class and fit.
TEST_F(RecognizerTest, EveryKernelSetGivesTheSameResults) {
    std::vector<esf::Points> clouds;
    for (const auto& shape : kShapes) clouds.push_back(held_out_view(shape, kHeldOut[0], 0));
    const esf::Recognizer reference(db_path_, {});
    for (const esf::Kernels kernels :
         {esf::Kernels::kAvx512, esf::Kernels::kAvx2, esf::Kernels::kPortable}) {
        if (!esf::kernels_supported(kernels)) continue;
        esf::RecognizerOptions options;
        options.kernels = kernels;
        const esf::Recognizer recognizer(db_path_, options);
        EXPECT_EQ(recognizer.info().setup.esf.kernels, kernels);
        for (const esf::Points& cloud : clouds) {
            EXPECT_EQ(recognizer.describe(cloud).signatures, reference.describe(cloud).signatures)
                << esf::to_string(kernels);
            const esf::Classification got = recognizer.classify(cloud);
            const esf::Classification want = reference.classify(cloud);
            EXPECT_EQ(got.class_name, want.class_name);
            EXPECT_EQ(got.best_model, want.best_model);
            ASSERT_EQ(got.neighbours.size(), want.neighbours.size());
            for (std::size_t n = 0; n < want.neighbours.size(); ++n) {
                EXPECT_EQ(got.neighbours[n].index, want.neighbours[n].index);
                EXPECT_EQ(got.neighbours[n].distance, want.neighbours[n].distance);
            }
            ASSERT_EQ(got.fit.has_value(), want.fit.has_value());
            if (want.fit) {
                EXPECT_EQ(got.fit->inliers, want.fit->inliers);
            }
        }
    }
}

TEST_F(RecognizerTest, BadCloudsThrowNamingTheDescriptor) {
    const esf::Recognizer recognizer(db_path_);
    const esf::Points two = {{0, 0, 1}, {0.1f, 0, 1}};
    EXPECT_CONTAINS(MESSAGE_OF(std::invalid_argument, recognizer.classify(two)),
                    "esf: needs at least 3 finite points, got 2");
    esf::Points line;
    for (int i = 0; i < 100; ++i) line.push_back({0.01f * float(i), 0, 1});
    EXPECT_CONTAINS(MESSAGE_OF(std::invalid_argument, recognizer.classify(line)), "esf: ");
    const std::vector<float> short_descriptor(10, 0.1f);
    EXPECT_CONTAINS(
        MESSAGE_OF(std::invalid_argument, recognizer.classify_descriptor(short_descriptor)),
        "10 floats is not one or more signatures of 640");
}

}  // namespace
