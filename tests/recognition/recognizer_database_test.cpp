// The recognizer's databases: missing, corrupt, empty or of settings this build cannot
// reproduce; multi-signature descriptors against brute force, and a baseline database end to end.

#include <gtest/gtest.h>

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
#include "esf/descriptors/descriptor.hpp"
#include "esf/descriptors/primitive_fit.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/knn_index.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"
#include "support/error_of.hpp"
#include "support/recognizer_fixture.hpp"
#include "support/require_baselines.hpp"

namespace fs = std::filesystem;

namespace {

using esf::test::kHeldOut;
using esf::test::kSamples;
using esf::test::kShapes;
using esf::test::RecognizerTest;
using esf::test::temp_dir;

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

TEST(RecognizerShape, TheQueryContrastIsItsDescriptorsCylinderBoxBlock) {
    const fs::path dir = temp_dir();
    const std::string angles = (dir / "angles.sqlite").string();
    const std::string plain = (dir / "plain.sqlite").string();
    const esf::DescriptorKind kind{
        "esf-angles", esf::kEsfVersion * 100 + esf::kSurfaceAnglesVersion, esf::kEsfAnglesSize};
    write_random_database(angles, kind, {}, 2, 3);
    write_random_database(plain, kEsfKind, {}, 2, 3);
    // A signature whose last block (the cylinder-box contrast) says 0.3, scaled as stored.
    std::vector<float> query(static_cast<std::size_t>(esf::kEsfAnglesSize), 0.001f);
    esf::PrimitiveFit fit;
    fit.cylinder = 0.3;
    const esf::PrimitiveHistogram h = esf::primitive_histogram(fit);
    std::transform(h.begin(), h.end(), query.end() - esf::kPrimitiveBins,
                   [](float v) { return 0.05f * v; });
    const esf::Recognizer recognizer(angles);
    EXPECT_NEAR(recognizer.shape_contrast(query), 0.3, 1e-6);
    EXPECT_NEAR(recognizer.classify_descriptor(query).shape_contrast, 0.3, 1e-6);
    EXPECT_TRUE(std::isnan(recognizer.shape_contrast(std::span(query).first(10))));
    // ESF alone has no such block.
    const esf::Recognizer esf_only(plain);
    const std::vector<float> esf_query(static_cast<std::size_t>(esf::kEsfSize), 0.001f);
    EXPECT_TRUE(std::isnan(esf_only.shape_contrast(esf_query)));
    EXPECT_TRUE(std::isnan(esf_only.classify_descriptor(esf_query).shape_contrast));
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

}  // namespace
