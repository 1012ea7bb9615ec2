// Training runs on small procedural meshes: what a database stores, resuming after an
// interruption or a killed process, failures that stay alone, camera distances.

#include "esf/training/training.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "esf/core/error.hpp"
#include "esf/descriptors/descriptor.hpp"
#include "esf/mesh/mesh.hpp"
#include "support/error_of.hpp"
#include "support/recursive_collada.hpp"
#include "support/training_fixture.hpp"

namespace esf::test {
namespace {

// KilledProcessResumesToTheSameDatabase runs this test binary again as a training process and
// kills it with SIGKILL. In that process, ESF_TRAINING_TEST_CHILD="ROOT DB MARKER" makes this
// object train ROOT into DB (creating MARKER after the first model is committed) and exit before
// any test runs.
struct TrainingChild {
    TrainingChild() {
        const char* spec = std::getenv("ESF_TRAINING_TEST_CHILD");
        if (!spec || !*spec) return;
        std::istringstream in(spec);
        std::string root, db_path, marker;
        in >> root >> db_path >> marker;
        try {
            Database db(db_path, OpenMode::kWrite);
            TrainingOptions o = fast_options();
            o.threads = 1;
            o.progress = [&](const TrainingProgress& p) {
                if (p.models_done == 1) std::ofstream(marker) << "1";
            };
            train(root, db, o);
        } catch (...) {
            _exit(3);
        }
        _exit(0);
    }
};
const TrainingChild training_child;

TEST_F(TrainingRunTest, StoresEveryViewAndTheSettings) {
    Database db(path("db.sqlite"), OpenMode::kWrite);
    std::vector<TrainingProgress> calls;
    TrainingOptions o = fast_options();
    o.progress = [&](const TrainingProgress& p) { calls.push_back(p); };
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_total, 4u);
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.models_failed, 0u);
    EXPECT_EQ(r.views + r.views_skipped, 4u * 20u);

    ASSERT_EQ(calls.size(), 5u);  // once at the start, once per model
    EXPECT_EQ(calls[0].models_done, 0u);
    EXPECT_EQ(calls[0].model, "");
    EXPECT_EQ(calls[1].model, "ball/egg");  // sorted order
    EXPECT_EQ(calls[4].model, "box/slab");
    EXPECT_EQ(calls[4].models_done, 4u);
    EXPECT_EQ(calls[4].views, r.views);

    const auto summary = db.summary();
    EXPECT_EQ(summary.models, 4u);
    EXPECT_EQ(summary.views, r.views);
    EXPECT_EQ(summary.skipped_views, r.views_skipped);
    EXPECT_EQ(db.settings(), training_settings(o, false));
    EXPECT_EQ(db.descriptor_kinds(), (std::vector<DescriptorKind>{{"esf", kEsfVersion, 640}}));
    for (const auto& m : db.models()) {
        EXPECT_EQ(m.group, m.name);  // no catalog: every model its own group
        EXPECT_EQ(m.scale, 1.0);
        for (const auto& v : db.views(m.category, m.name)) {
            if (v.skipped()) continue;
            ASSERT_EQ(v.descriptors.size(), 640u);
            double sum = 0.0;
            for (float x : v.descriptors) sum += x;
            EXPECT_NEAR(sum, 1.0, 1e-4);  // an ESF histogram sums to one
            EXPECT_GE(v.points, o.min_points);
            // The pose is rigid.
            const Eigen::Matrix3f rot = v.pose.topLeftCorner<3, 3>();
            EXPECT_TRUE((rot * rot.transpose()).isIdentity(1e-4f));
        }
    }
    const DescriptorMatrix matrix = db.load_descriptors();
    EXPECT_EQ(matrix.rows(), r.views);
    EXPECT_EQ(matrix.categories, (std::vector<std::string>{"ball", "box"}));
}

TEST_F(TrainingRunTest, OccludedCopiesAreMoreSignaturesOfTheirView) {
    TrainingOptions o = fast_options();
    Database plain(path("plain.sqlite"), OpenMode::kWrite);
    train(root(), plain, o);
    o.occlusions = 2;
    {
        Database occluded(path("occluded.sqlite"), OpenMode::kWrite);
        const TrainingResult r = train(root(), occluded, o);
        EXPECT_EQ(occluded.settings(), training_settings(o, false));
        std::size_t copies = 0;
        for (const auto& m : occluded.models()) {
            const auto views = occluded.views(m.category, m.name);
            const auto own = plain.views(m.category, m.name);
            ASSERT_EQ(views.size(), own.size());
            for (std::size_t i = 0; i < views.size(); ++i) {
                ASSERT_EQ(views[i].skipped(), own[i].skipped());
                if (views[i].skipped()) continue;
                // The view's own signature first, as without copies; then up to two copies, each
                // another ESF histogram (summing to one), each unlike the view's own.
                const auto& d = views[i].descriptors;
                ASSERT_EQ(d.size() % 640u, 0u);
                ASSERT_GE(d.size(), 640u);
                ASSERT_LE(d.size(), 3u * 640u);
                EXPECT_TRUE(
                    std::equal(own[i].descriptors.begin(), own[i].descriptors.end(), d.begin()));
                for (std::size_t s = 640; s < d.size(); s += 640) {
                    double sum = 0.0, differs = 0.0;
                    for (std::size_t j = 0; j < 640; ++j) {
                        sum += d[s + j];
                        differs += std::abs(d[s + j] - d[j]);
                    }
                    EXPECT_NEAR(sum, 1.0, 1e-4);
                    EXPECT_GT(differs, 0.01);
                    ++copies;
                }
            }
        }
        EXPECT_GT(copies, r.views);  // most views have both copies (a copy needs min_points points)
        EXPECT_EQ(occluded.load_descriptors().rows(), r.views + copies);
    }

    // Resuming with another number of copies is refused, naming the setting.
    o.occlusions = 1;
    Database again(path("occluded.sqlite"), OpenMode::kWrite);
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(root(), again, o); }),
                    "occlusions 1 (database: 2)");
    o.occlusions = kMaxTrainingOcclusions + 1;
    Database fresh(path("fresh.sqlite"), OpenMode::kWrite);
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(root(), fresh, o); }),
                    "occlusions must be at most");
}

TEST_F(TrainingRunTest, ResultDoesNotDependOnThreadCount) {
    TrainingOptions o = fast_options();
    o.threads = 1;
    Database one(path("one.sqlite"), OpenMode::kWrite);
    train(root(), one, o);
    o.threads = 3;
    Database three(path("three.sqlite"), OpenMode::kWrite);
    train(root(), three, o);
    expect_same(snapshot(one), snapshot(three));
}

TEST_F(TrainingRunTest, InterruptedRunResumesToTheSameDatabase) {
    const TrainingOptions o = fast_options();
    Database full(path("full.sqlite"), OpenMode::kWrite);
    train(root(), full, o);

    struct Killed {};
    const std::string db_path = path("resumed.sqlite");
    {
        Database db(db_path, OpenMode::kWrite);
        TrainingOptions killing = o;
        killing.progress = [](const TrainingProgress& p) {
            if (p.models_done == 2) throw Killed{};  // as if killed after the second commit
        };
        EXPECT_THROW(train(root(), db, killing), Killed);
        EXPECT_EQ(db.summary().models, 2u);
    }
    Database db(db_path, OpenMode::kWrite);
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_existing, 2u);
    EXPECT_EQ(r.models_trained, 2u);
    expect_same(snapshot(full), snapshot(db));
    // Nothing left to do the third time.
    const TrainingResult again = train(root(), db, o);
    EXPECT_EQ(again.models_existing, 4u);
    EXPECT_EQ(again.models_trained, 0u);
    expect_same(snapshot(full), snapshot(db));
}

TEST_F(TrainingRunTest, NewModelsAreAddedWithoutChangingOthers) {
    const TrainingOptions o = fast_options();
    Database full(path("full.sqlite"), OpenMode::kWrite);
    train(root(), full, o);

    fs::rename(path("root/box"), path("later_box"));
    Database db(path("grown.sqlite"), OpenMode::kWrite);
    EXPECT_EQ(train(root(), db, o).models_trained, 2u);
    fs::rename(path("later_box"), path("root/box"));
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_existing, 2u);
    EXPECT_EQ(r.models_trained, 2u);
    expect_same(snapshot(full), snapshot(db));
}

TEST_F(TrainingRunTest, OtherSettingsAreRefusedOnResume) {
    Database db(path("db.sqlite"), OpenMode::kWrite);
    TrainingOptions o = fast_options();
    o.progress = [](const TrainingProgress& p) {
        if (p.models_done == 1) throw std::runtime_error("stop");
    };
    EXPECT_THROW(train(root(), db, o), std::runtime_error);
    o.progress = nullptr;
    o.seed = 8;
    o.esf.samples = 3000;
    const std::string message = error_of<std::invalid_argument>([&] { train(root(), db, o); });
    EXPECT_CONTAINS(message, path("db.sqlite") + ": database was trained with other settings: ");
    EXPECT_CONTAINS(message, "esf_samples 3000 (database: 2000)");
    EXPECT_CONTAINS(message, "seed 8 (database: 7)");
    EXPECT_EQ(db.summary().models, 1u);  // untouched
    o = fast_options();
    o.render.level = 1;
    EXPECT_CONTAINS(error_of<std::invalid_argument>([&] { train(root(), db, o); }),
                    "view_sphere_level 1 (database: 0)");
}

TEST_F(TrainingRunTest, BrokenMeshesAreStoredAsFailedAndRetried) {
    touch("root/box/broken.ply", "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n");
    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, fast_options());
    EXPECT_EQ(r.models_total, 5u);
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.models_failed, 1u);
    ASSERT_EQ(r.failures.size(), 1u);
    EXPECT_EQ(r.failures[0].model, "box/broken");
    EXPECT_CONTAINS(r.failures[0].error, "broken.ply");
    EXPECT_EQ(db.model_status("box", "broken"), ModelStatus::kFailed);
    EXPECT_EQ(db.summary().failed_models, 1u);

    // Fixed file: the next run retries it and stores it.
    write_ply_mesh(path("root/box/broken.ply"), box_mesh(0.05f, 0.1f, 0.15f));
    const TrainingResult again = train(root(), db, fast_options());
    EXPECT_EQ(again.models_existing, 4u);
    EXPECT_EQ(again.models_trained, 1u);
    EXPECT_EQ(db.model_status("box", "broken"), ModelStatus::kComplete);
    EXPECT_EQ(db.summary().failed_models, 0u);
}

TEST_F(TrainingRunTest, AMeshThatCrashesTheImporterFailsAloneAndTrainingGoesOn) {
    touch("root/box/recursive.dae", test::recursive_collada());
    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, fast_options());
    EXPECT_EQ(r.models_total, 5u);
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.models_failed, 1u);
    ASSERT_EQ(r.failures.size(), 1u);
    EXPECT_EQ(r.failures[0].model, "box/recursive");
    EXPECT_EQ(r.failures[0].error.rfind(path("root/box/recursive.dae") + ": the mesh importer ", 0),
              0u)
        << r.failures[0].error;
    EXPECT_EQ(db.model_status("box", "recursive"), ModelStatus::kFailed);
    EXPECT_EQ(db.model_status("box", "cube"), ModelStatus::kComplete);
}

TEST_F(TrainingRunTest, SymbolicLinkLoopsAreReportedAndTrainingGoesOn) {
    fs::create_symlink("loop.ply", dir_ / "root" / "box" / "loop.ply");  // points at itself
    fs::create_symlink("looping", dir_ / "root" / "looping");            // a category folder too
    const auto models = find_models(root());
    ASSERT_EQ(models.size(), 5u);  // the four meshes and the looping file; no "looping" category
    EXPECT_EQ(models[3].file, "box/loop.ply");  // ball/egg, ball/sphere, box/cube, box/loop, ...

    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, fast_options());
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.models_failed, 1u);
    ASSERT_EQ(r.failures.size(), 1u);
    EXPECT_EQ(r.failures[0].model, "box/loop");
    EXPECT_CONTAINS(r.failures[0].error, "loop.ply: cannot read: ");
    EXPECT_CONTAINS(r.failures[0].error, "symbolic links");
    EXPECT_EQ(db.model_status("box", "loop"), ModelStatus::kFailed);
}

TEST_F(TrainingRunTest, ASecondWriterIsRefusedAndNothingMixes) {
    const TrainingOptions o = fast_options();
    Database first(path("db.sqlite"), OpenMode::kWrite);
    // Another training on the same new database, while the first holds it: refused at open.
    EXPECT_EQ(error_of<IoError>([&] { Database second(path("db.sqlite"), OpenMode::kWrite); }),
              path("db.sqlite") + ": database is in use by another training");
    train(root(), first, o);
    {
        const Database reader(path("db.sqlite"));  // readers are never refused
        EXPECT_EQ(reader.summary().models, 4u);
    }
    EXPECT_THROW(Database(path("db.sqlite"), OpenMode::kWrite), IoError);
    first = Database(path("other.sqlite"), OpenMode::kWrite);  // the lock goes with the writer
    Database again(path("db.sqlite"), OpenMode::kWrite);
    EXPECT_EQ(train(root(), again, o).models_existing, 4u);
}

TEST_F(TrainingRunTest, ViewsWithTooFewPointsAreSkippedAndCounted) {
    TrainingOptions o = fast_options();
    o.min_points = 1'000'000;  // no view has that many: every one is skipped
    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, o);
    EXPECT_EQ(r.models_trained, 4u);
    EXPECT_EQ(r.views, 0u);
    EXPECT_EQ(r.views_skipped, 80u);
    const auto views = db.views("box", "cube");
    ASSERT_EQ(views.size(), 20u);
    EXPECT_TRUE(views[0].skipped());
    EXPECT_GT(views[0].points, 0u);
    EXPECT_EQ(views[0].skip_reason,
              "too few points (" + std::to_string(views[0].points) + " < 1000000)");
    EXPECT_EQ(db.summary().skipped_views, 80u);
    EXPECT_EQ(db.load_descriptors().rows(), 0u);
}

TEST_F(TrainingRunTest, CatalogRescalesNonMetricModelsAndSetsGroups) {
    // The cube is "non-metric" with a 0.1 extent: scaled to the box category's metric median,
    // which is the slab's 0.2. The sphere keeps its size and gets a shared group.
    touch("root/catalog.csv",
          "file,category,source,model,group,extent,metric\n"
          "box/cube.ply,box,kit,cube,boxes,0.1,no\n"
          "box/slab.ply,box,ycb,slab,slab,0.2,yes\n"
          "ball/sphere.ply,ball,ycb,sphere,round,0.1,yes\n");
    Database db(path("db.sqlite"), OpenMode::kWrite);
    train(root(), db, fast_options());
    EXPECT_EQ(db.settings().at("rescale_non_metric"), SettingValue(std::string("category_extent")));
    const auto models = db.models();  // ball/egg, ball/sphere, box/cube, box/slab
    ASSERT_EQ(models.size(), 4u);
    EXPECT_EQ(models[0].group, "egg");  // not in the catalog: metric, own group
    EXPECT_EQ(models[0].scale, 1.0);
    EXPECT_EQ(models[1].group, "round");
    EXPECT_EQ(models[1].scale, 1.0);
    EXPECT_EQ(models[2].group, "boxes");
    EXPECT_DOUBLE_EQ(models[2].scale, 2.0);
    EXPECT_EQ(models[3].scale, 1.0);

    // Without the catalog the same database is refused (the scales would differ).
    TrainingOptions o = fast_options();
    o.use_catalog = false;
    const std::string refused = error_of<std::invalid_argument>([&] { train(root(), db, o); });
    EXPECT_CONTAINS(refused, "rescale_non_metric none (database: category_extent)");
    EXPECT_CONTAINS(refused, "pass --catalog with the catalog it was trained with");
}

TEST_F(TrainingRunTest, DatabasesFromBeforeTheCameraSettingsResume) {
    // A database written before the camera band and range existed has no such settings; it was
    // trained from the whole sphere at one distance, so those options resume it.
    const TrainingOptions o = fast_options();
    Database db(path("db.sqlite"), OpenMode::kWrite);
    train(root(), db, o);
    Settings old = db.settings();
    for (const char* key : {"camera_max_distance", "camera_min_elevation", "camera_max_elevation"})
        ASSERT_EQ(old.erase(key), 1u) << key;
    db.set_settings(old);
    const TrainingResult again = train(root(), db, o);
    EXPECT_EQ(again.models_existing, again.models_total);
    // The new defaults are refused, naming what differs and what to do.
    TrainingOptions upper = o;
    upper.render.min_elevation = 0.0;
    const std::string message = error_of<std::invalid_argument>([&] { train(root(), db, upper); });
    EXPECT_CONTAINS(message, "camera_min_elevation 0 (database: unset)");
    EXPECT_CONTAINS(message, "train with the same options to resume, or into a new database");
}

TEST_F(TrainingRunTest, KilledProcessResumesToTheSameDatabase) {
    Database full(path("full.sqlite"), OpenMode::kWrite);
    train(root(), full, fast_options());

    const std::string db_path = path("killed.sqlite"), marker = path("marker");
    const std::string spec = "ESF_TRAINING_TEST_CHILD=" + root() + " " + db_path + " " + marker;
    std::string self = fs::read_symlink("/proc/self/exe").string();
    char* argv[] = {self.data(), nullptr};
    char* envp[] = {const_cast<char*>(spec.c_str()), nullptr};
    pid_t child = 0;
    ASSERT_EQ(posix_spawn(&child, self.c_str(), nullptr, nullptr, argv, envp), 0);
    for (int i = 0; i < 6000 && !fs::exists(marker); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    kill(child, SIGKILL);  // somewhere in models 2 to 4 (or just after, on a fast machine)
    int status = 0;
    waitpid(child, &status, 0);
    ASSERT_TRUE(fs::exists(marker)) << "the training process never committed a model";
    EXPECT_TRUE(WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) == 0));

    {
        const Database killed(db_path);  // readable as it is, log and all
        for (const auto& m : killed.models()) EXPECT_EQ(m.views + m.skipped_views, 20u);
    }
    // The writer's lock goes with the killed process. A mesh importer it was starting at that
    // moment shares the lock's file until its exec (posix_spawn's child closes the descriptor
    // there), so the lock may outlive the process by that instant: allow it a few seconds.
    std::optional<Database> reopened;
    for (int i = 0; i < 500 && !reopened; ++i) {
        try {
            reopened.emplace(db_path, OpenMode::kWrite);
        } catch (const IoError& e) {
            ASSERT_NE(std::string(e.what()).find("in use by another training"), std::string::npos)
                << e.what();
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
    }
    ASSERT_TRUE(reopened.has_value()) << "the killed training's lock never went";
    Database& db = *reopened;
    const TrainingResult r = train(root(), db, fast_options());
    EXPECT_GE(r.models_existing, 1u);
    expect_same(snapshot(full), snapshot(db));
}

TEST_F(TrainingRunTest, ViewsAreTakenFromTheCameraDistanceOrFarEnoughToSeeTheModel) {
    EXPECT_EQ(TrainingOptions{}.render.distance, kTrainingCameraDistance);  // the default
    TrainingOptions o = fast_options();
    o.render.distance = 0.12;  // metres from each model's centre
    Database db(path("db.sqlite"), OpenMode::kWrite);
    const TrainingResult r = train(root(), db, o);
    ASSERT_EQ(r.models_failed, 0u);
    const auto camera_distance = [&](const std::string& category, const std::string& name) {
        const auto views = db.views(category, name);
        EXPECT_EQ(views.size(), 20u);
        // Every model is centred on its origin, which each camera looks at from its distance.
        return views.at(7).pose.block<3, 1>(0, 3).norm();
    };
    // The sphere (radius 0.05) fits: seen from 0.12 m. The cube's bounding sphere (radius
    // 0.05 sqrt 3 = 0.0866) would not fit: seen from 1.5 times that radius, 0.1299 m.
    EXPECT_NEAR(camera_distance("ball", "sphere"), 0.12, 1e-5);
    EXPECT_NEAR(camera_distance("box", "cube"), 1.5 * 0.05 * std::sqrt(3.0), 1e-4);
}

}  // namespace
}  // namespace esf::test
