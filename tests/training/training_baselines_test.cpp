// Training with the PCL baseline descriptors: they describe the views of the ESF database,
// reproduce them from the stored settings, resume and skip what they cannot describe.

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "esf/core/error.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/training/training.hpp"
#include "support/error_of.hpp"
#include "support/require_baselines.hpp"
#include "support/training_fixture.hpp"

namespace esf::test {
namespace {

TrainingOptions baseline_options(const std::string& descriptor) {
    TrainingOptions o = fast_options();
    o.descriptor = descriptor;
    return o;
}

/// Sums of each `dimension`-float signature of a view.
std::vector<double> signature_sums(const std::vector<float>& descriptors, std::size_t dimension) {
    std::vector<double> sums(descriptors.size() / dimension, 0.0);
    for (std::size_t i = 0; i < descriptors.size(); ++i) sums[i / dimension] += descriptors[i];
    return sums;
}

TEST_F(TrainingRunTest, BaselinesDescribeTheViewsOfTheEsfDatabase) {
    ESF_REQUIRE_BASELINES();
    Database esf_db(path("esf.sqlite"), OpenMode::kWrite);
    train(root(), esf_db, fast_options());
    const Snapshot esf = snapshot(esf_db);

    for (const std::string name : {"vfh", "cvfh"}) {
        SCOPED_TRACE(name);
        Database db(path(name + ".sqlite"), OpenMode::kWrite);
        const TrainingResult r = train(root(), db, baseline_options(name));
        EXPECT_EQ(r.models_trained, 4u);
        EXPECT_EQ(r.views + r.views_skipped, 80u);
        EXPECT_GT(r.views, 60u);
        EXPECT_EQ(db.descriptor_kinds(),
                  (std::vector<DescriptorKind>{{name, kBaselineDescriptorVersion, 308}}));
        EXPECT_EQ(db.settings(), training_settings(baseline_options(name), false));

        const Snapshot s = snapshot(db);
        ASSERT_EQ(s.models.size(), esf.models.size());
        std::size_t signatures = 0, multi = 0;
        for (std::size_t m = 0; m < s.models.size(); ++m) {
            SCOPED_TRACE(s.models[m].name);
            EXPECT_EQ(s.models[m].name, esf.models[m].name);
            EXPECT_EQ(s.models[m].scale, esf.models[m].scale);
            ASSERT_EQ(s.views[m].size(), 20u);
            for (std::size_t v = 0; v < s.views[m].size(); ++v) {
                const ViewEntry& view = s.views[m][v];
                const ViewEntry& same = esf.views[m][v];
                // The same rendering: index, point count and pose bit for bit.
                EXPECT_EQ(view.index, same.index);
                EXPECT_EQ(view.points, same.points);
                EXPECT_EQ(view.pose, same.pose);
                if (same.skipped()) {
                    EXPECT_TRUE(view.skipped());  // too few points for both
                }
                if (view.skipped()) {
                    EXPECT_FALSE(view.skip_reason.empty());
                    continue;
                }
                ASSERT_EQ(view.descriptors.size() % 308, 0u);
                const auto sums = signature_sums(view.descriptors, 308);
                ASSERT_GE(sums.size(), 1u);
                if (name == "vfh") {
                    EXPECT_EQ(sums.size(), 1u);
                }
                for (const double sum : sums) EXPECT_NEAR(sum, 1.0, 1e-4);
                for (const float x : view.descriptors) EXPECT_GE(x, 0.0f);
                signatures += sums.size();
                multi += sums.size() > 1;
            }
        }
        const DescriptorMatrix matrix = db.load_descriptors();
        EXPECT_EQ(matrix.kind.name, name);
        EXPECT_EQ(matrix.rows(), signatures);  // every signature is a row
        if (name == "cvfh") {
            EXPECT_GT(multi, 0u) << "no view of a box has several regions";
        }
    }
}

TEST_F(TrainingRunTest, BaselineViewsAreReproducedFromTheStoredSettings) {
    ESF_REQUIRE_BASELINES();
    // A query described with the settings the database stores (what Recognizer's query_setup()
    // reads) matches the stored descriptor of the same view exactly, and its L1 nearest
    // neighbour is that view.
    Database db(path("vfh.sqlite"), OpenMode::kWrite);
    const TrainingOptions o = baseline_options("vfh");
    train(root(), db, o);
    const Settings settings = db.settings();
    DescriptorOptions query;
    query.leaf_factor = static_cast<float>(std::get<double>(settings.at("descriptor_leaf_factor")));
    query.normal_radius_factor =
        static_cast<float>(std::get<double>(settings.at("descriptor_normal_radius_factor")));
    query.remove_outliers = std::get<std::int64_t>(settings.at("descriptor_remove_outliers")) == 1;
    query.samples = static_cast<int>(std::get<std::int64_t>(settings.at("descriptor_samples")));
    const auto vfh = make_descriptor(std::get<std::string>(settings.at("descriptor")), query);

    RenderOptions render = o.render;
    render.seed = model_seed(o.seed, "box", "slab");
    const MeshRenderer renderer(load_mesh(path("root/box/slab.ply")), render);
    const auto stored = db.views("box", "slab");
    const DescriptorMatrix matrix = db.load_descriptors();
    int checked = 0;
    for (const std::size_t v : {std::size_t{3}, std::size_t{11}}) {
        if (stored[v].skipped()) continue;
        const std::vector<Signature> described = vfh->compute(renderer.render_view(v).points);
        ASSERT_EQ(described.size(), 1u);
        EXPECT_EQ(described[0], stored[v].descriptors);  // bit-exact
        std::size_t best = 0;
        double best_distance = std::numeric_limits<double>::infinity();
        for (std::size_t row = 0; row < matrix.rows(); ++row) {
            double d = 0.0;
            for (std::size_t i = 0; i < 308; ++i)
                d += std::abs(double(matrix.row(row)[i]) - double(described[0][i]));
            if (d < best_distance) best_distance = d, best = row;
        }
        const DescriptorRow& nearest = matrix.row_info[best];
        EXPECT_EQ(matrix.categories[nearest.category], "box");
        EXPECT_EQ(matrix.models[nearest.model].name, "slab");
        EXPECT_EQ(nearest.view_index, static_cast<int>(v));
        EXPECT_EQ(best_distance, 0.0);
        ++checked;
    }
    EXPECT_GT(checked, 0);
}

TEST_F(TrainingRunTest, BaselineDatabasesResumeAndRefuseAnotherDescriptor) {
    ESF_REQUIRE_BASELINES();
    const TrainingOptions o = baseline_options("vfh");
    Database full(path("full.sqlite"), OpenMode::kWrite);
    train(root(), full, o);

    Database db(path("resumed.sqlite"), OpenMode::kWrite);
    TrainingOptions stopping = o;
    stopping.threads = 1;  // and another thread count
    stopping.progress = [](const TrainingProgress& p) {
        if (p.models_done == 2) throw std::runtime_error("stop");
    };
    EXPECT_THROW(train(root(), db, stopping), std::runtime_error);
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_existing, 2u);
    EXPECT_EQ(r.models_trained, 2u);
    expect_same(snapshot(full), snapshot(db));  // vfh is deterministic: bit-exact

    // Another descriptor into it, or vfh into an esf database: refused, naming both.
    std::string message =
        error_of<std::invalid_argument>([&] { train(root(), db, baseline_options("cvfh")); });
    EXPECT_CONTAINS(message, path("resumed.sqlite") + ": database holds vfh descriptors, not cvfh");
    EXPECT_CONTAINS(message, "(setting descriptor cvfh, database: vfh)");
    message = error_of<std::invalid_argument>([&] { train(root(), db, fast_options()); });
    EXPECT_CONTAINS(message, "database holds vfh descriptors, not esf");
    Database esf_db(path("esf.sqlite"), OpenMode::kWrite);
    TrainingOptions one_model = fast_options();
    one_model.progress = [](const TrainingProgress& p) {
        if (p.models_done == 1) throw std::runtime_error("stop");
    };
    EXPECT_THROW(train(root(), esf_db, one_model), std::runtime_error);
    message = error_of<std::invalid_argument>([&] { train(root(), esf_db, o); });
    EXPECT_CONTAINS(message, "database holds esf descriptors, not vfh");
    EXPECT_EQ(esf_db.summary().models, 1u);  // untouched
    EXPECT_EQ(db.descriptor_kinds().size(), 1u);

    // Other baseline options are differences like any other.
    TrainingOptions other = o;
    other.descriptor_options.leaf_factor = 2.0f;
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(root(), db, other); }),
                    "descriptor_leaf_factor 2 (database: 3)");
}

TEST_F(TrainingRunTest, ViewsABaselineCannotDescribeAreSkippedAndCounted) {
    ESF_REQUIRE_BASELINES();
    // With a leaf of 40 mesh resolutions, the voxel grid leaves a handful of points, fewer than
    // the baseline preprocessing needs: every view is skipped with the descriptor's reason.
    TrainingOptions o = baseline_options("vfh");
    o.descriptor_options.leaf_factor = 40.0f;
    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.models_failed, 0u);
    EXPECT_EQ(r.views + r.views_skipped, 80u);
    EXPECT_GT(r.views_skipped, 0u);
    std::size_t described_by_vfh = 0;
    for (const auto& m : db.models())
        for (const auto& v : db.views(m.category, m.name))
            if (v.skipped() && v.skip_reason.rfind("vfh: ", 0) == 0) ++described_by_vfh;
    EXPECT_GT(described_by_vfh, 0u);
    EXPECT_EQ(db.summary().skipped_views, r.views_skipped);
}

}  // namespace
}  // namespace esf::test
