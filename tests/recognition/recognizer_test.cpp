#include "esf/recognition/recognizer.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/recognition/knn_index.hpp"
#include "esf/render/render.hpp"
#include "esf/render/view_sphere.hpp"
#include "esf/shapes/shape_generator.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"
#include "support/error_of.hpp"
#include "support/require_baselines.hpp"
#include "support/test_data.hpp"

namespace fs = std::filesystem;

namespace {

/// The message of the exception `expr` throws, of type `type` ("" when it does not throw).
#define MESSAGE_OF(type, expr)                          \
    [&]() -> std::string {                              \
        try {                                           \
            expr;                                       \
        } catch (const type& e) {                       \
            return e.what();                            \
        }                                               \
        ADD_FAILURE() << #expr " did not throw " #type; \
        return std::string();                           \
    }()

fs::path temp_dir() {
    const fs::path dir = fs::temp_directory_path() /
                         ("esf_recognizer_test_" + std::to_string(::getpid()) + "_" +
                          ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

constexpr int kSamples = 4000;
const std::vector<std::string> kShapes = {"bowl", "mug"};

/// A database of one procedural mug and one bowl, 80 views each (view sphere level 1, as the
/// paper and `esf train` use), trained once for the whole suite. (With 20 views, a mug seen from
/// the side away from its handle is taken for the bowl under some seeds.)
class RecognizerTest : public ::testing::Test {
  protected:
    static void SetUpTestSuite() {
        root_ = fs::temp_directory_path() / ("esf_recognizer_suite_" + std::to_string(::getpid()));
        fs::remove_all(root_);
        for (const auto& shape : kShapes) {
            fs::create_directories(root_ / "meshes" / shape);
            meshes_[shape] = esf::generate_shape(shape, 7, 0);
            esf::write_ply_mesh((root_ / "meshes" / shape / (shape + "_a.ply")).string(),
                                meshes_[shape]);
        }
        db_path_ = (root_ / "two.sqlite").string();
        esf::Database db(db_path_, esf::OpenMode::kWrite);
        esf::TrainingOptions options;  // the paper's ESF from the whole view sphere at 0.8 m
        options.descriptor = "esf";
        options.render.min_elevation = -90.0;
        options.render.distance = 0.8;
        options.render.max_distance.reset();
        options.render.level = 1;
        options.esf.samples = kSamples;
        options.seed = 5;
        esf::train((root_ / "meshes").string(), db, options);
    }
    static void TearDownTestSuite() { fs::remove_all(root_); }

    /// A view of `shape` from a direction between the view sphere's cameras, at the training
    /// camera distance, with the training sensor noise.
    static esf::Points held_out_view(const std::string& shape, const Eigen::Vector3d& direction,
                                     std::uint64_t key) {
        esf::RenderOptions options;
        options.level = 0;
        options.seed = 99;
        const esf::MeshRenderer renderer(meshes_[shape], options);
        const Eigen::Vector3d centre = renderer.centre() * renderer.scale();
        const Eigen::Vector3d eye = centre + renderer.camera_distance() * direction.normalized();
        return renderer.render_pose(esf::look_at(eye, centre), key);
    }

    static inline fs::path root_;
    static inline std::string db_path_;
    static inline std::map<std::string, esf::Mesh> meshes_;
};

// Directions as far from the view sphere's cameras as they come: 17 to 20 degrees from the
// nearest one (vertices and edge midpoints of the level-1 tessellation).
const std::vector<Eigen::Vector3d> kHeldOut = {
    {0.95, 0.0, 0.59}, {0.0, 1.06, 0.0}, {-0.89, -0.55, 0.34}, {0.57, -0.92, 0.0}};

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
    const esf::Recognizer recognizer(db_path_);
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

/// All rows by (weighted) L1 distance to `query`, nearest first, ties by row.
std::vector<BruteForceRow> brute_force(const esf::DescriptorMatrix& m, std::span<const float> query,
                                       const std::vector<float>& weights) {
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
    return out;
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
                std::vector<BruteForceRow> expected = brute_force(m, q.signatures, weights);
                if (per_model) {  // the first (nearest) row of each model
                    std::set<std::uint32_t> seen;
                    std::erase_if(expected, [&](const BruteForceRow& r) {
                        return !seen.insert(m.row_info[r.row].model).second;
                    });
                }
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

// ---- database errors ------------------------------------------------------------------------

/// Writes a database of `models` models x `views` views with seeded random signatures of `kind`
/// (1 + view % signatures_max signatures per view).
void write_random_database(const std::string& path, const esf::DescriptorKind& kind,
                           const esf::Settings& settings, int models, int views,
                           int signatures_max = 1, std::uint64_t seed = 1) {
    esf::Database db(path, esf::OpenMode::kWrite);
    db.set_settings(settings);
    db.add_descriptor_kind(kind);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    for (int m = 0; m < models; ++m) {
        esf::ModelEntry model;
        model.category = m % 2 ? "odd" : "even";
        model.name = "model_" + std::to_string(m);
        model.file = model.category + "/" + model.name + ".ply";
        for (int v = 0; v < views; ++v) {
            esf::ViewEntry view;
            view.index = v;
            view.points = 100;
            view.pose(0, 3) = float(m);
            view.pose(1, 3) = float(v);
            const int signatures = 1 + v % signatures_max;
            for (int s = 0; s < signatures; ++s) {
                std::vector<float> sig(static_cast<std::size_t>(kind.dimension));
                double sum = 0.0;
                for (float& x : sig) sum += (x = uniform(rng));
                for (float& x : sig) x = static_cast<float>(x / sum);
                view.descriptors.insert(view.descriptors.end(), sig.begin(), sig.end());
            }
            model.views.push_back(std::move(view));
        }
        db.write_model(model, kind.name);
    }
}

const esf::DescriptorKind kEsfKind{"esf", esf::kEsfVersion, esf::kEsfSize};

TEST(RecognizerErrors, MissingOrCorruptDatabaseNamesTheFile) {
    const fs::path dir = temp_dir();
    const std::string missing = (dir / "missing.sqlite").string();
    EXPECT_CONTAINS(MESSAGE_OF(esf::IoError, esf::Recognizer{missing}), missing);
    const std::string corrupt = (dir / "corrupt.sqlite").string();
    {
        std::ofstream out(corrupt, std::ios::binary);
        for (int i = 0; i < 4096; ++i) out.put(static_cast<char>((i * 7919) & 0xff));
    }
    const std::string message = MESSAGE_OF(esf::IoError, esf::Recognizer{corrupt});
    EXPECT_EQ(message.rfind(corrupt, 0), 0u) << message;
    EXPECT_EQ(fs::file_size(corrupt), 4096u);  // read-only: untouched
    fs::remove_all(dir);
}

TEST(RecognizerErrors, EmptyDatabase) {
    const fs::path dir = temp_dir();
    const std::string empty = (dir / "empty.sqlite").string();
    { esf::Database db(empty, esf::OpenMode::kWrite); }
    std::string message = MESSAGE_OF(std::invalid_argument, esf::Recognizer{empty});
    EXPECT_EQ(message.rfind(empty, 0), 0u) << message;
    EXPECT_CONTAINS(message, "empty database: no descriptors");

    const std::string no_views = (dir / "no_views.sqlite").string();
    {
        esf::Database db(no_views, esf::OpenMode::kWrite);
        db.add_descriptor_kind(kEsfKind);
    }
    message = MESSAGE_OF(std::invalid_argument, esf::Recognizer{no_views});
    EXPECT_CONTAINS(message, no_views + ": empty database: no views with esf descriptors");
    fs::remove_all(dir);
}

TEST(RecognizerErrors, OtherDescriptorVersionOrUnknownDescriptor) {
    const fs::path dir = temp_dir();
    const std::string v2 = (dir / "v2.sqlite").string();
    write_random_database(v2, {"esf", esf::kEsfVersion + 1, esf::kEsfSize}, {}, 2, 3);
    std::string message = MESSAGE_OF(std::invalid_argument, esf::Recognizer{v2});
    EXPECT_CONTAINS(message,
                    v2 + ": descriptor esf version " + std::to_string(esf::kEsfVersion + 1) +
                        ", but this build computes version " + std::to_string(esf::kEsfVersion));

    const std::string unknown = (dir / "unknown.sqlite").string();
    write_random_database(unknown, {"spin_image", 1, 153}, {}, 2, 3);
    message = MESSAGE_OF(std::invalid_argument, esf::Recognizer{unknown});
    EXPECT_CONTAINS(message, unknown + ": unknown descriptor 'spin_image' (valid: esf");

    const std::string settings = (dir / "settings.sqlite").string();
    write_random_database(settings, kEsfKind,
                          {{"descriptor", std::string("esf")},
                           {"descriptor_version", std::int64_t{esf::kEsfVersion + 3}}},
                          2, 3);
    message = MESSAGE_OF(std::invalid_argument, esf::Recognizer{settings});
    EXPECT_CONTAINS(message,
                    "setting descriptor_version = " + std::to_string(esf::kEsfVersion + 3) +
                        ", but this build computes esf version");
    fs::remove_all(dir);
}

TEST(RecognizerErrors, SettingsThisBuildCannotReproduce) {
    const auto message = [](const esf::Settings& s, const esf::DescriptorKind& k = kEsfKind) {
        return MESSAGE_OF(std::invalid_argument, esf::query_setup(s, k));
    };
    EXPECT_CONTAINS(message({{"esf_samples", std::string("many")}}),
                    "setting esf_samples = many is not an integer");
    EXPECT_CONTAINS(message({{"esf_grid_size", std::int64_t{3}}}), "esf settings: ");
    EXPECT_CONTAINS(message({{"esf_sampler", std::string("quantum")}}), "quantum");
    EXPECT_CONTAINS(message({{"seed", std::int64_t{-4}}}), "setting seed = -4 < 0");
    EXPECT_CONTAINS(message({{"descriptor_dimension", std::int64_t{320}}}),
                    "setting descriptor_dimension = 320, but esf has 640 floats");
    EXPECT_CONTAINS(message({}, {"esf", esf::kEsfVersion, 320}),
                    "descriptor esf has 320 floats, but this build computes 640");
    EXPECT_CONTAINS(message({{"descriptor_remove_outliers", std::int64_t{2}}}, {"vfh", 1, 308}),
                    "descriptor_remove_outliers = 2 is not 0 or 1");
    // What is stored is what queries use; missing keys take the defaults.
    const esf::QuerySetup setup = esf::query_setup({{"esf_samples", std::int64_t{1234}},
                                                    {"esf_grid_size", std::int64_t{32}},
                                                    {"seed", std::string("18446744073709551615")}},
                                                   kEsfKind);
    EXPECT_EQ(setup.esf.samples, 1234);
    EXPECT_EQ(setup.esf.grid_size, 32);
    EXPECT_EQ(setup.esf.seed, 18446744073709551615ull);
    EXPECT_EQ(setup.esf.sampler, esf::EsfSampler::kFast);
    const esf::QuerySetup vfh = esf::query_setup(
        {{"descriptor_leaf_factor", 2.0}, {"descriptor_remove_outliers", std::int64_t{0}}},
        {"vfh", 1, 308});
    EXPECT_EQ(vfh.options.leaf_factor, 2.0f);
    EXPECT_FALSE(vfh.options.remove_outliers);
    EXPECT_EQ(esf::descriptor_version("esf"), esf::kEsfVersion);
    EXPECT_CONTAINS(MESSAGE_OF(std::invalid_argument, esf::descriptor_version("nope")),
                    "unknown descriptor 'nope'");
}

TEST(RecognizerErrors, BadOptionsAndSeveralKinds) {
    const fs::path dir = temp_dir();
    const std::string path = (dir / "db.sqlite").string();
    write_random_database(path, kEsfKind, {}, 2, 3);
    esf::RecognizerOptions zero;
    zero.k = 0;
    EXPECT_CONTAINS(MESSAGE_OF(std::invalid_argument, esf::Recognizer(path, zero)), "k must be");
    esf::RecognizerOptions absent;
    absent.descriptor = "vfh";
    EXPECT_CONTAINS(MESSAGE_OF(std::invalid_argument, esf::Recognizer(path, absent)),
                    path + ": the database holds no vfh descriptors");
    esf::Database(path, esf::OpenMode::kWrite).add_descriptor_kind({"vfh", 1, 308});
    EXPECT_CONTAINS(MESSAGE_OF(std::invalid_argument, esf::Recognizer{path}),
                    "several descriptors (esf, vfh); choose one");
    esf::RecognizerOptions pick;
    pick.descriptor = "esf";
    EXPECT_EQ(esf::Recognizer(path, pick).info().views, 6u);
    fs::remove_all(dir);
}

// ---- multi-signature descriptors ------------------------------------------------------------

struct BruteForceView {
    double distance;
    std::uint32_t model;
    int view;
    bool operator<(const BruteForceView& o) const {
        return std::tie(distance, model, view) < std::tie(o.distance, o.model, o.view);
    }
};

/// Views by their distance to a multi-signature query: the minimum of the L1 distance over every
/// (row of the view, query signature) pair; nearest first.
std::vector<BruteForceView> brute_force_views(const esf::DescriptorMatrix& m,
                                              std::span<const float> query) {
    const auto dim = static_cast<std::size_t>(m.kind.dimension);
    std::map<std::pair<std::uint32_t, int>, double> best;
    for (std::size_t r = 0; r < m.rows(); ++r)
        for (std::size_t s = 0; s < query.size(); s += dim) {
            double d = 0.0;
            for (std::size_t i = 0; i < dim; ++i)
                d += std::abs(double(m.row(r)[i]) - double(query[s + i]));
            const auto key = std::make_pair(m.row_info[r].model, m.row_info[r].view_index);
            const auto it = best.find(key);
            if (it == best.end() || d < it->second) best[key] = d;
        }
    std::vector<BruteForceView> out;
    for (const auto& [key, d] : best) out.push_back({d, key.first, key.second});
    std::sort(out.begin(), out.end());
    return out;
}

TEST(RecognizerMultiSignature, ViewDistanceIsTheBestPairOfSignatures) {
    ESF_REQUIRE_BASELINES();
    const fs::path dir = temp_dir();
    const std::string path = (dir / "cvfh.sqlite").string();
    const esf::DescriptorKind kind{"cvfh", 1, 308};
    write_random_database(path, kind, {{"descriptor", std::string("cvfh")}}, 6, 12, 3);
    esf::RecognizerOptions options;
    options.k = 7;
    options.one_view_per_model = false;
    const esf::Recognizer recognizer(path, options);
    options.one_view_per_model = true;
    const esf::Recognizer per_model(path, options);
    EXPECT_EQ(recognizer.info().views, 72u);
    EXPECT_EQ(recognizer.info().rows, 72u / 3 * (1 + 2 + 3));
    EXPECT_TRUE(recognizer.classifier().index().grouped());

    const esf::DescriptorMatrix m = esf::Database(path).load_descriptors();
    std::mt19937_64 rng(42);
    std::uniform_int_distribution<std::size_t> pick(0, m.rows() - 1);
    std::normal_distribution<float> jitter(0.0f, 2e-4f);
    for (int trial = 0; trial < 5; ++trial) {
        // Query signatures near random rows, so the nearest views are not all alike.
        std::vector<float> query;
        const std::size_t signatures = 1 + static_cast<std::size_t>(trial % 3);
        for (std::size_t s = 0; s < signatures; ++s)
            for (const float v : m.row(pick(rng))) query.push_back(std::max(0.0f, v + jitter(rng)));
        const auto expected = brute_force_views(m, query);
        const esf::Classification c = recognizer.classify_descriptor(query);
        ASSERT_EQ(c.neighbours.size(), 7u);
        for (std::size_t n = 0; n < 7; ++n) {
            EXPECT_EQ(c.neighbours[n].model_name, m.models[expected[n].model].name);
            EXPECT_EQ(c.neighbours[n].view, expected[n].view);
            EXPECT_NEAR(c.neighbours[n].distance, expected[n].distance, 1e-9);
        }
        // One view per model: the nearest view of each of the 6 models.
        std::vector<BruteForceView> first;
        std::set<std::uint32_t> seen;
        for (const BruteForceView& v : expected)
            if (seen.insert(v.model).second) first.push_back(v);
        const esf::Classification p = per_model.classify_descriptor(query);
        ASSERT_EQ(p.neighbours.size(), 6u);
        for (std::size_t n = 0; n < 6; ++n) {
            EXPECT_EQ(p.neighbours[n].model_name, m.models[first[n].model].name);
            EXPECT_EQ(p.neighbours[n].view, first[n].view);
            EXPECT_NEAR(p.neighbours[n].distance, first[n].distance, 1e-9);
        }
    }
    fs::remove_all(dir);
}

TEST_F(RecognizerTest, BaselineDescriptorDatabaseEndToEnd) {
    ESF_REQUIRE_BASELINES();
    // The training views of the mug and the bowl described with CVFH (one or more signatures a
    // view) through the descriptor registry, stored as a database of kind cvfh.
    const fs::path dir = temp_dir();
    const std::string path = (dir / "cvfh.sqlite").string();
    const auto cvfh = esf::make_descriptor("cvfh");
    {
        esf::Database db(path, esf::OpenMode::kWrite);
        db.set_settings({{"descriptor", std::string("cvfh")}});
        db.add_descriptor_kind({"cvfh", 1, 308});
        for (const auto& shape : kShapes) {
            esf::RenderOptions render;
            render.level = 0;
            const std::vector<esf::RenderedView> views = esf::render_views(meshes_[shape], render);
            esf::ModelEntry model;
            model.category = shape;
            model.name = shape + "_a";
            model.file = shape + "/" + shape + "_a.ply";
            model.views.resize(views.size());
            esf::parallel_for(views.size(), 0, [&](std::size_t v) {
                esf::ViewEntry& view = model.views[v];
                view.index = views[v].index;
                view.points = views[v].points.size();
                view.pose = views[v].pose;
                try {
                    for (const esf::Signature& sig : cvfh->compute(views[v].points))
                        view.descriptors.insert(view.descriptors.end(), sig.begin(), sig.end());
                } catch (const std::invalid_argument& e) {
                    view.skip_reason = e.what();
                }
            });
            db.write_model(model, "cvfh");
        }
    }
    const esf::Recognizer recognizer(path);
    EXPECT_EQ(recognizer.info().setup.kind.name, "cvfh");
    EXPECT_FALSE(recognizer.info().weighted);
    const esf::DescriptorMatrix m = esf::Database(path).load_descriptors();
    EXPECT_EQ(recognizer.info().rows, m.rows());
    EXPECT_GT(m.rows(), recognizer.info().views);  // some views have several smooth regions
    for (const auto& shape : kShapes) {
        const esf::Points view = held_out_view(shape, kHeldOut[3], 11);
        // The query is described as the database was.
        std::vector<float> expected;
        for (const esf::Signature& sig : cvfh->compute(view))
            expected.insert(expected.end(), sig.begin(), sig.end());
        const esf::QueryDescriptor q = recognizer.describe(view);
        ASSERT_TRUE(q.ok()) << q.error;
        EXPECT_EQ(q.signatures, expected);
        const esf::Classification c = recognizer.classify(view);
        std::vector<BruteForceView> truth = brute_force_views(m, q.signatures);
        std::set<std::uint32_t> seen;  // one view per model (the default)
        std::erase_if(truth, [&](const BruteForceView& v) { return !seen.insert(v.model).second; });
        ASSERT_EQ(c.neighbours.size(), std::min<std::size_t>(10, truth.size()));
        for (std::size_t n = 0; n < c.neighbours.size(); ++n) {
            EXPECT_EQ(c.neighbours[n].model_name, m.models[truth[n].model].name) << n;
            EXPECT_EQ(c.neighbours[n].view, truth[n].view) << n;
            EXPECT_NEAR(c.neighbours[n].distance, truth[n].distance, 1e-9) << n;
        }
    }
    fs::remove_all(dir);
}

// ---- scenes ---------------------------------------------------------------------------------

TEST_F(RecognizerTest, SyntheticSceneWithTwoObjects) {
    // The mug and the bowl on a table (world z up), seen from 0.9 m at 35 degrees elevation.
    const esf::Mesh& mug = meshes_["mug"];
    const esf::Mesh& bowl = meshes_["bowl"];
    Eigen::Isometry3d mug_pose = Eigen::Isometry3d::Identity();
    mug_pose.translation() = Eigen::Vector3d(0.0, 0.15, 0.0);
    Eigen::Isometry3d bowl_pose = Eigen::Isometry3d::Identity();
    bowl_pose.translation() = Eigen::Vector3d(0.05, -0.15, 0.0);
    const std::vector<esf::SceneObject> objects = {{&mug, mug_pose}, {&bowl, bowl_pose}};
    esf::SceneOptions scene_options;
    scene_options.table_plane = true;
    scene_options.table_half_size = 0.6;
    scene_options.noise = esf::SensorNoise::kKinect;
    scene_options.seed = 3;
    const Eigen::Isometry3d camera = esf::look_at({0.75, 0.1, 0.5}, {0, 0, 0.05});
    const esf::PointCloud scene = esf::render_scene(objects, camera, scene_options);

    for (const int threads : {1, 2}) {
        esf::RecognizerOptions options;
        options.threads = threads;
        const esf::Recognizer recognizer(db_path_, options);
        esf::SegmentationOptions segmentation;
        segmentation.threads = threads;
        // The objects stand apart; convexity grouping cuts the mug's handle off at its joints.
        segmentation.grouping = esf::Grouping::kEuclidean;
        const esf::SceneRecognition result = recognizer.recognize_scene(scene, segmentation);
        EXPECT_TRUE(result.plane_found);
        ASSERT_EQ(result.objects.size(), 2u) << result.message;
        for (const esf::RecognizedObject& o : result.objects) {
            ASSERT_TRUE(o.classified()) << o.error;
            // The object's world position tells which it is.
            const Eigen::Vector3d world = camera.inverse() * o.cluster.centroid.cast<double>();
            const std::string truth = world.y() > 0 ? "mug" : "bowl";
            EXPECT_EQ(o.classification.class_name, truth) << "centroid " << world.transpose();
            EXPECT_EQ(o.classification.neighbours.size(),
                      std::min<std::size_t>(10, recognizer.info().models));
            EXPECT_GT(o.cluster.points.size(), 300u);
        }
    }
}

/// A 1 m x 1 m table at z = 1 (camera frame, facing the camera) sampled every 5 mm.
esf::Points table_points() {
    esf::Points table;
    for (int i = 0; i < 200; ++i)
        for (int j = 0; j < 200; ++j)
            table.push_back({-0.5f + 0.005f * float(i), -0.5f + 0.005f * float(j), 1.0f});
    return table;
}

TEST_F(RecognizerTest, ClustersThatCannotBeDescribedAreReportedPerObject) {
    esf::Points scene = table_points();
    // A solid block 5 cm above the table (towards the camera: smaller z)...
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j)
            for (int k = 0; k < 10; ++k)
                scene.push_back(
                    {0.2f + 0.005f * float(i), 0.005f * float(j), 0.95f - 0.005f * float(k)});
    // ...two isolated points far from everything...
    scene.push_back({-0.3f, -0.3f, 0.9f});
    scene.push_back({-0.3f, -0.3f, 0.905f});
    // ...and a thin straight wire: one line.
    for (int k = 0; k < 40; ++k) scene.push_back({-0.3f, 0.3f, 0.98f - 0.004f * float(k)});
    esf::SegmentationOptions segmentation;
    segmentation.min_cluster_points = 1;
    segmentation.grouping = esf::Grouping::kEuclidean;  // a solid block: no surface to patch
    const esf::Recognizer recognizer(db_path_);
    const esf::SceneRecognition result = recognizer.recognize_scene(
        esf::PointCloud{scene, static_cast<std::uint32_t>(scene.size()), 1, {}, {}}, segmentation);
    ASSERT_TRUE(result.plane_found);
    ASSERT_EQ(result.objects.size(), 3u) << result.message;
    EXPECT_EQ(result.objects[0].cluster.points.size(), 1000u);
    EXPECT_TRUE(result.objects[0].classified()) << result.objects[0].error;
    EXPECT_EQ(result.objects[1].cluster.points.size(), 40u);
    EXPECT_FALSE(result.objects[1].classified());
    EXPECT_CONTAINS(result.objects[1].error, "esf: ");
    EXPECT_EQ(result.objects[2].cluster.points.size(), 2u);
    EXPECT_FALSE(result.objects[2].classified());
    EXPECT_CONTAINS(result.objects[2].error, "esf: needs at least 3 finite points, got 2");
}

TEST_F(RecognizerTest, SceneWithoutPlaneOrObjectsSaysSo) {
    const esf::Recognizer recognizer(db_path_);
    esf::Points table = table_points();
    const esf::SceneRecognition empty = recognizer.recognize_scene(
        esf::PointCloud{table, static_cast<std::uint32_t>(table.size()), 1, {}, {}});
    EXPECT_TRUE(empty.plane_found);
    EXPECT_TRUE(empty.objects.empty());
    EXPECT_CONTAINS(empty.message, "no objects");

    std::mt19937_64 rng(3);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    esf::Points cloud;
    for (int i = 0; i < 5000; ++i) cloud.push_back({u(rng), u(rng), 2.0f + u(rng)});
    const esf::SceneRecognition none = recognizer.recognize_scene(
        esf::PointCloud{cloud, static_cast<std::uint32_t>(cloud.size()), 1, {}, {}});
    EXPECT_FALSE(none.plane_found);
    EXPECT_TRUE(none.objects.empty());
    EXPECT_CONTAINS(none.message, "no dominant plane");
}

TEST_F(RecognizerTest, RealSceneObjectsAreSegmentedAndClassified) {
    ESF_REQUIRE_DATA("real/scenes/mosd_learn0.pcd");
    const esf::PointCloud scene =
        esf::read_cloud(esf::test::data_file("real/scenes/mosd_learn0.pcd").string());
    ASSERT_EQ(scene.labels.size(), scene.points.size());
    // Labelled objects: label / 10 >= 2 is object label / 10 - 1.
    std::map<std::uint32_t, std::size_t> labelled;
    for (const std::uint32_t l : scene.labels)
        if (l >= 20) ++labelled[l / 10];
    ASSERT_FALSE(labelled.empty());

    const esf::Recognizer recognizer(db_path_);
    const esf::SceneRecognition result = recognizer.recognize_scene(scene);
    ASSERT_TRUE(result.plane_found) << result.message;
    // Every cluster has a class, and most of every labelled object of a fair size lies in one
    // cluster (two touching objects may share one).
    std::map<std::uint32_t, std::size_t> most;  // object -> its points in its best cluster
    for (const esf::RecognizedObject& o : result.objects) {
        EXPECT_TRUE(o.classified()) << o.error;
        EXPECT_TRUE(o.classification.class_name == "mug" || o.classification.class_name == "bowl");
        std::map<std::uint32_t, std::size_t> inside;
        for (const std::uint32_t i : o.cluster.indices) ++inside[scene.labels[i] / 10];
        for (const auto& [object, n] : inside) most[object] = std::max(most[object], n);
    }
    for (const auto& [object, points] : labelled)
        if (points >= 2000) {
            EXPECT_GE(2 * most[object], points) << "object " << object;
        }
}

}  // namespace
