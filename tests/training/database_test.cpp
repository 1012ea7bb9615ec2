#include "esf/training/database.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <thread>

#include "esf/core/error.hpp"
#include "support/error_of.hpp"

namespace esf {
namespace {

namespace fs = std::filesystem;

class DatabaseTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("esf_database_test_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string file(const std::string& name) const { return (dir_ / name).string(); }

    fs::path dir_;
};

const DescriptorKind kEsf{"esf", 1, 640};

/// A view whose descriptor values encode (model tag, view, bin), so mix-ups show.
ViewEntry make_view(int index, float tag, int signatures = 1, int dim = 640) {
    ViewEntry v;
    v.index = index;
    v.points = 1000 + static_cast<std::size_t>(index);
    v.pose = Eigen::Matrix4f::Identity();
    v.pose(0, 3) = static_cast<float>(index);
    v.pose(1, 3) = tag;
    v.pose(2, 0) = 0.25f;  // not symmetric: a transposed pose would show
    for (int s = 0; s < signatures; ++s)
        for (int i = 0; i < dim; ++i)
            v.descriptors.push_back(tag + 0.001f * static_cast<float>(index) +
                                    1e-6f * static_cast<float>(i + s * dim));
    return v;
}

ModelEntry make_model(const std::string& category, const std::string& name, float tag,
                      int views = 3) {
    ModelEntry m;
    m.category = category;
    m.name = name;
    m.file = category + "/" + name + ".ply";
    m.group = "g_" + name;
    m.scale = 1.5;
    for (int i = 0; i < views; ++i) m.views.push_back(make_view(i, tag));
    return m;
}

/// prefix + number (GCC 12 warns falsely about "literal" + std::to_string()).
std::string indexed(const std::string& prefix, int i) {
    std::string out = prefix;
    out += std::to_string(i);
    return out;
}

/// Runs one SQL statement on a file with the plain SQLite API (to damage databases on purpose).
void raw_sql(const std::string& path, const std::string& sql) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    char* error = nullptr;
    const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error);
    const std::string message = error ? error : "";
    sqlite3_free(error);
    sqlite3_close(db);
    ASSERT_EQ(rc, SQLITE_OK) << message;
}

template <class F>
std::string io_error_of(F&& f) {
    try {
        f();
    } catch (const IoError& e) {
        return e.what();
    }
    return "(no IoError)";
}

template <class F>
std::string invalid_argument_of(F&& f) {
    try {
        f();
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "(no std::invalid_argument)";
}

TEST_F(DatabaseTest, ModelRoundTripsExactly) {
    const std::string path = file("db.sqlite");
    ModelEntry model = make_model("mug", "blue", 0.5f);
    model.views[1].descriptors.clear();
    model.views[1].skip_reason = "too few points (12 < 50)";
    model.views[1].points = 12;
    {
        Database db(path, OpenMode::kWrite);
        db.add_descriptor_kind(kEsf);
        db.write_model(model, "esf");
    }
    const Database db(path);  // read-only
    const auto views = db.views("mug", "blue");
    ASSERT_EQ(views.size(), 3u);
    for (std::size_t i = 0; i < views.size(); ++i) {
        EXPECT_EQ(views[i].index, model.views[i].index);
        EXPECT_EQ(views[i].points, model.views[i].points);
        EXPECT_EQ(views[i].pose, model.views[i].pose);
        EXPECT_EQ(views[i].descriptors, model.views[i].descriptors);  // bit-exact floats
        EXPECT_EQ(views[i].skip_reason, model.views[i].skip_reason);
    }
    EXPECT_TRUE(views[1].skipped());
    const auto models = db.models();
    ASSERT_EQ(models.size(), 1u);
    EXPECT_EQ(models[0].category, "mug");
    EXPECT_EQ(models[0].name, "blue");
    EXPECT_EQ(models[0].file, "mug/blue.ply");
    EXPECT_EQ(models[0].group, "g_blue");
    EXPECT_EQ(models[0].scale, 1.5);
    EXPECT_EQ(models[0].status, ModelStatus::kComplete);
    EXPECT_EQ(models[0].views, 2u);
    EXPECT_EQ(models[0].skipped_views, 1u);
    EXPECT_EQ(db.model_status("mug", "blue"), ModelStatus::kComplete);
    EXPECT_EQ(db.model_status("mug", "red"), std::nullopt);
    EXPECT_EQ(db.model_status("cup", "blue"), std::nullopt);
}

TEST_F(DatabaseTest, GroupDefaultsToModelName) {
    Database db(file("db.sqlite"), OpenMode::kWrite);
    db.add_descriptor_kind(kEsf);
    ModelEntry m = make_model("box", "tea", 1.0f, 1);
    m.group.clear();
    db.write_model(m, "esf");
    EXPECT_EQ(db.models().at(0).group, "tea");
}

TEST_F(DatabaseTest, SettingsKeepTheirTypesAndExactValues) {
    const std::string path = file("db.sqlite");
    const Settings settings = {
        {"seed", std::int64_t{-3}}, {"big", std::int64_t{std::numeric_limits<std::int64_t>::max()}},
        {"fill_fraction", 0.1},     {"fx", 525.0},
        {"third", 1.0 / 3.0},       {"noise", std::string("kinect")}};
    {
        Database db(path, OpenMode::kWrite);
        EXPECT_TRUE(db.settings().empty());
        db.set_settings({{"old", std::string("gone")}});
        db.set_settings(settings);  // replaces
    }
    const Settings read = Database(path).settings();
    EXPECT_EQ(read, settings);
    EXPECT_TRUE(std::holds_alternative<double>(read.at("fx")));
    EXPECT_TRUE(std::holds_alternative<std::int64_t>(read.at("seed")));
    EXPECT_EQ(to_string(read.at("fill_fraction")), "0.1");
    EXPECT_EQ(to_string(read.at("fx")), "525");
    EXPECT_EQ(std::stod(to_string(read.at("third"))), 1.0 / 3.0);
    EXPECT_EQ(to_string(read.at("seed")), "-3");
    EXPECT_EQ(to_string(read.at("noise")), "kinect");
}

TEST_F(DatabaseTest, DescriptorKindsAreRegisteredOnce) {
    Database db(file("db.sqlite"), OpenMode::kWrite);
    db.add_descriptor_kind(kEsf);
    db.add_descriptor_kind(kEsf);  // same again: no-op
    EXPECT_EQ(db.descriptor_kinds(), std::vector<DescriptorKind>{kEsf});
    EXPECT_CONTAINS(invalid_argument_of([&] {
                        db.add_descriptor_kind({"esf", 2, 640});
                    }),
                    ("descriptor 'esf' is stored with version 1 and dimension 640, not "
                     "version 2 and dimension 640"));
    EXPECT_CONTAINS(invalid_argument_of([&] {
                        db.add_descriptor_kind({"vfh", 1, 0});
                    }),
                    ("dimension must be > 0"));
    EXPECT_CONTAINS(invalid_argument_of([&] { db.write_model(make_model("a", "b", 0), "vfh"); }),
                    ("no descriptors of kind 'vfh' (stored: esf)"));
}

TEST_F(DatabaseTest, WriteModelRejectsBadInput) {
    Database db(file("db.sqlite"), OpenMode::kWrite);
    EXPECT_CONTAINS(invalid_argument_of([&] { db.write_model(make_model("a", "b", 0), ""); }),
                    ("no descriptors stored"));
    db.add_descriptor_kind(kEsf);

    ModelEntry m = make_model("mug", "m", 0.0f);
    m.views[2].index = 0;
    EXPECT_CONTAINS(invalid_argument_of([&] { db.write_model(m, "esf"); }),
                    ("model 'mug/m' view 0: duplicate view index"));
    m = make_model("mug", "m", 0.0f);
    m.views[1].descriptors.pop_back();
    EXPECT_CONTAINS(invalid_argument_of([&] { db.write_model(m, "esf"); }),
                    ("view 1: 639 descriptor values, not a multiple of 640 (esf)"));
    m = make_model("mug", "m", 0.0f);
    m.views[0].descriptors[5] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_CONTAINS(invalid_argument_of([&] { db.write_model(m, "esf"); }),
                    ("view 0: non-finite descriptor value"));
    m = make_model("mug", "m", 0.0f);
    m.views[0].pose(0, 0) = std::numeric_limits<float>::infinity();
    EXPECT_CONTAINS(invalid_argument_of([&] { db.write_model(m, "esf"); }),
                    ("view 0: non-finite pose"));
    m = make_model("mug", "m", 0.0f);
    m.error = "cannot load";
    EXPECT_CONTAINS(invalid_argument_of([&] { db.write_model(m, "esf"); }),
                    ("a failed model has no views"));
    m = make_model("", "m", 0.0f);
    EXPECT_CONTAINS(invalid_argument_of([&] { db.write_model(m, "esf"); }),
                    ("empty category or name"));
    m = make_model("mug", "m", 0.0f);
    m.scale = 0.0;
    EXPECT_CONTAINS(invalid_argument_of([&] { db.write_model(m, "esf"); }),
                    ("scale must be finite and > 0"));
    EXPECT_TRUE(db.models().empty());  // nothing half-written
}

TEST_F(DatabaseTest, FailedModelsAreStoredAndReplaced) {
    Database db(file("db.sqlite"), OpenMode::kWrite);
    db.add_descriptor_kind(kEsf);
    ModelEntry failed;
    failed.category = "mug";
    failed.name = "broken";
    failed.file = "mug/broken.obj";
    failed.error = "mug/broken.obj: no triangles";
    db.write_model(failed, "esf");
    db.write_model(make_model("mug", "fine", 1.0f), "esf");
    EXPECT_EQ(db.model_status("mug", "broken"), ModelStatus::kFailed);
    auto s = db.summary();
    EXPECT_EQ(s.models, 1u);
    EXPECT_EQ(s.failed_models, 1u);
    EXPECT_EQ(db.models().at(0).error, "mug/broken.obj: no triangles");
    EXPECT_EQ(db.load_descriptors().models.size(), 1u);  // failed models have no rows

    // Writing the model again replaces it, views and all.
    db.write_model(make_model("mug", "broken", 2.0f, 2), "esf");
    EXPECT_EQ(db.model_status("mug", "broken"), ModelStatus::kComplete);
    s = db.summary();
    EXPECT_EQ(s.models, 2u);
    EXPECT_EQ(s.failed_models, 0u);
    EXPECT_EQ(s.views, 5u);
    db.write_model(make_model("mug", "broken", 3.0f, 1), "esf");
    EXPECT_EQ(db.summary().views, 4u);
    EXPECT_EQ(db.load_descriptors().rows(), 4u);
    EXPECT_EQ(db.views("mug", "broken").at(0).descriptors, make_view(0, 3.0f).descriptors);
}

TEST_F(DatabaseTest, SummaryCountsPerCategory) {
    Database db(file("db.sqlite"), OpenMode::kWrite);
    db.add_descriptor_kind(kEsf);
    db.write_model(make_model("mug", "a", 1.0f, 4), "esf");
    ModelEntry b = make_model("mug", "b", 2.0f, 3);
    b.views[0].descriptors.clear();
    b.views[0].skip_reason = "degenerate";
    db.write_model(b, "esf");
    db.write_model(make_model("box", "c", 3.0f, 2), "esf");
    ModelEntry failed;
    failed.category = "can";
    failed.name = "d";
    failed.error = "boom";
    db.write_model(failed, "esf");

    const auto s = db.summary();
    EXPECT_EQ(s.models, 3u);
    EXPECT_EQ(s.failed_models, 1u);
    EXPECT_EQ(s.views, 8u);  // 4 + 2 + 2
    EXPECT_EQ(s.skipped_views, 1u);
    ASSERT_EQ(s.categories.size(), 3u);
    EXPECT_EQ(s.categories[0].name, "box");
    EXPECT_EQ(s.categories[0].models, 1u);
    EXPECT_EQ(s.categories[1].name, "can");
    EXPECT_EQ(s.categories[1].models, 0u);
    EXPECT_EQ(s.categories[1].failed_models, 1u);
    EXPECT_EQ(s.categories[2].name, "mug");
    EXPECT_EQ(s.categories[2].models, 2u);
    EXPECT_EQ(s.categories[2].views, 6u);
    EXPECT_EQ(s.categories[2].skipped_views, 1u);
    EXPECT_EQ(s.descriptor_kinds, std::vector<DescriptorKind>{kEsf});
}

TEST_F(DatabaseTest, LoadDescriptorsIsOrderedByNameNotInsertion) {
    Database db(file("db.sqlite"), OpenMode::kWrite);
    db.add_descriptor_kind(kEsf);
    // Inserted out of order, views too.
    ModelEntry z = make_model("mug", "z", 3.0f, 2);
    std::swap(z.views[0], z.views[1]);
    db.write_model(z, "esf");
    db.write_model(make_model("mug", "a", 2.0f, 2), "esf");
    ModelEntry box = make_model("box", "k", 1.0f, 3);
    box.views[1].descriptors.clear();  // skipped views have no row
    box.views[1].skip_reason = "too few points";
    db.write_model(box, "esf");

    const DescriptorMatrix m = db.load_descriptors();
    EXPECT_EQ(m.kind, kEsf);
    EXPECT_EQ(m.categories, (std::vector<std::string>{"box", "mug"}));
    ASSERT_EQ(m.models.size(), 3u);
    EXPECT_EQ(m.models[0].name, "k");
    EXPECT_EQ(m.models[1].name, "a");
    EXPECT_EQ(m.models[2].name, "z");
    ASSERT_EQ(m.rows(), 6u);
    ASSERT_EQ(m.data.size(), 6u * 640u);
    // (category, model, view): box/k 0, box/k 2, mug/a 0, mug/a 1, mug/z 0, mug/z 1
    const int expect_category[] = {0, 0, 1, 1, 1, 1};
    const int expect_model[] = {0, 0, 1, 1, 2, 2};
    const int expect_view[] = {0, 2, 0, 1, 0, 1};
    const float expect_tag[] = {1.0f, 1.0f, 2.0f, 2.0f, 3.0f, 3.0f};
    for (std::size_t r = 0; r < m.rows(); ++r) {
        SCOPED_TRACE(r);
        EXPECT_EQ(m.row_info[r].category, static_cast<std::uint32_t>(expect_category[r]));
        EXPECT_EQ(m.row_info[r].model, static_cast<std::uint32_t>(expect_model[r]));
        EXPECT_EQ(m.row_info[r].view_index, expect_view[r]);
        EXPECT_EQ(m.row_info[r].signature, 0);
        const ViewEntry v = make_view(expect_view[r], expect_tag[r]);
        EXPECT_EQ(m.row_info[r].pose, v.pose);
        const auto row = m.row(r);
        EXPECT_TRUE(std::equal(row.begin(), row.end(), v.descriptors.begin()));
    }
}

TEST_F(DatabaseTest, SeveralKindsAndSignaturesPerView) {
    Database db(file("db.sqlite"), OpenMode::kWrite);
    db.add_descriptor_kind(kEsf);
    db.add_descriptor_kind({"cvfh", 1, 4});
    ModelEntry m;
    m.category = "mug";
    m.name = "a";
    m.views = {make_view(0, 1.0f, 3, 4), make_view(1, 2.0f, 1, 4)};
    db.write_model(m, "cvfh");
    EXPECT_CONTAINS(invalid_argument_of([&] { db.load_descriptors(); }),
                    ("several descriptor kinds stored (cvfh, esf); name the one to use"));
    const DescriptorMatrix cvfh = db.load_descriptors("cvfh");
    ASSERT_EQ(cvfh.rows(), 4u);
    EXPECT_EQ(cvfh.row_info[0].signature, 0);
    EXPECT_EQ(cvfh.row_info[2].signature, 2);
    EXPECT_EQ(cvfh.row_info[3].view_index, 1);
    EXPECT_EQ(cvfh.row(2)[0], m.views[0].descriptors[8]);
    EXPECT_EQ(db.load_descriptors("esf").rows(), 0u);
    EXPECT_EQ(db.views("mug", "a", "cvfh").at(0).descriptors, m.views[0].descriptors);
}

TEST_F(DatabaseTest, WeightsRoundTrip) {
    const std::string path = file("db.sqlite");
    const std::vector<float> w = {1.0f, 0.5f, 0.25f, 2.0f, 1.0f, 1.0f, 0.75f, 3.0f, 1.0f, 0.125f};
    {
        Database db(path, OpenMode::kWrite);
        db.add_descriptor_kind(kEsf);
        EXPECT_EQ(db.weights(), std::nullopt);
        db.set_weights(std::vector<float>(10, 9.0f));
        db.set_weights(w);  // replaces
        EXPECT_CONTAINS(invalid_argument_of([&] { db.set_weights(std::vector<float>{}); }),
                        ("weights are empty"));
        EXPECT_CONTAINS(invalid_argument_of([&] {
                            db.set_weights(std::vector<float>{1.0f, std::nanf("")});
                        }),
                        ("weight 1 is nan: weights must be positive and finite"));
        // Zero, negative and infinite weights are refused too: a zero weight makes every view
        // of that block equally near.
        for (const float bad : {0.0f, -1.0f, std::numeric_limits<float>::infinity()})
            EXPECT_CONTAINS(invalid_argument_of([&] {
                                db.set_weights(std::vector<float>{1.0f, 2.0f, bad});
                            }),
                            ("weight 2 is "));
        EXPECT_EQ(db.weights(), w);  // the refused ones changed nothing
    }
    EXPECT_EQ(Database(path).weights("esf"), w);
}

TEST_F(DatabaseTest, WeightsAreIgnoredOnceTheDatabaseChanged) {
    const std::string path = file("db.sqlite");
    const std::vector<float> w(10, 2.0f);
    Database db(path, OpenMode::kWrite);
    db.add_descriptor_kind(kEsf);
    db.write_model(make_model("mug", "a", 1.0f), "esf");
    const std::string learned_on = db.content_fingerprint();
    EXPECT_EQ(learned_on.size(), 16u);
    db.set_weights(w, "esf", learned_on);
    EXPECT_FALSE(db.weights_are_stale());
    EXPECT_EQ(db.weights(), w);
    EXPECT_EQ(Database(path).weights(), w);

    // A category added by training: the weights stay stored but are stale and not applied.
    db.write_model(make_model("box", "b", 2.0f), "esf");
    EXPECT_NE(db.content_fingerprint(), learned_on);
    EXPECT_TRUE(db.weights_are_stale());
    EXPECT_EQ(db.weights(), std::nullopt);
    EXPECT_EQ(db.stored_weights(), w);
    EXPECT_TRUE(Database(path).weights_are_stale());

    // Weights learned before that change are refused when stored; learned anew they apply.
    EXPECT_CONTAINS(io_error_of([&] { db.set_weights(w, "esf", learned_on); }),
                    (path + ": the database changed while its weights were learned"));
    EXPECT_TRUE(db.weights_are_stale());
    db.set_weights(w, "esf", db.content_fingerprint());
    EXPECT_EQ(db.weights(), w);

    // A model replaced by one with fewer views changes it too; rewriting the same does not.
    const std::string now = db.content_fingerprint();
    db.write_model(make_model("box", "b", 2.0f), "esf");
    EXPECT_EQ(db.content_fingerprint(), now);
    db.write_model(make_model("box", "b", 2.0f, 2), "esf");
    EXPECT_NE(db.content_fingerprint(), now);
}

TEST_F(DatabaseTest, WeightsOfAFileWithoutTheirBasisAreStale) {
    // Files written before weights recorded what they were learned on: the weights are kept
    // but not applied (the database may have changed since).
    const std::string path = file("db.sqlite");
    {
        Database db(path, OpenMode::kWrite);
        db.add_descriptor_kind(kEsf);
        db.write_model(make_model("mug", "a", 1.0f), "esf");
        db.set_weights(std::vector<float>(10, 2.0f));
    }
    raw_sql(path, "DROP TABLE weights_basis;");
    const Database db(path);
    EXPECT_TRUE(db.weights_are_stale());
    EXPECT_EQ(db.weights(), std::nullopt);
    EXPECT_EQ(db.stored_weights(), std::vector<float>(10, 2.0f));
}

TEST_F(DatabaseTest, OneWriterAtATime) {
    const std::string path = file("db.sqlite");
    std::optional<Database> writer(std::in_place, path, OpenMode::kWrite);
    EXPECT_EQ(io_error_of([&] { Database other(path, OpenMode::kWrite); }),
              path + ": database is in use by another training");
    writer->add_descriptor_kind(kEsf);
    writer->write_model(make_model("mug", "a", 1.0f), "esf");
    EXPECT_EQ(Database(path).summary().models, 1u);  // a reader is never refused
    writer.reset();
    Database next(path, OpenMode::kWrite);
    EXPECT_EQ(next.summary().models, 1u);
}

TEST_F(DatabaseTest, ReadOnlyOpenNeverCreatesOrWrites) {
    const std::string path = file("missing.sqlite");
    EXPECT_EQ(io_error_of([&] { Database db(path); }), path + ": no such file");
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(fs::is_empty(dir_));

    const std::string made = file("db.sqlite");
    {
        Database db(made, OpenMode::kWrite);
        db.add_descriptor_kind(kEsf);
        db.write_model(make_model("mug", "a", 1.0f), "esf");
    }
    const auto before = fs::last_write_time(made);
    Database db(made);
    EXPECT_FALSE(db.writable());
    EXPECT_CONTAINS(
        invalid_argument_of([&] { db.write_model(make_model("mug", "b", 1.0f), "esf"); }),
        (made + ": database is opened read-only"));
    EXPECT_CONTAINS(invalid_argument_of([&] { db.set_settings({}); }), ("read-only"));
    EXPECT_EQ(db.summary().models, 1u);
    EXPECT_EQ(fs::last_write_time(made), before);
    // Only the database itself: no journal or other side files.
    EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(DatabaseTest, NotADatabaseNamesTheFile) {
    const std::string text = file("notes.txt");
    std::ofstream(text) << "category,model\nmug,a\n";
    EXPECT_EQ(io_error_of([&] { Database db(text); }),
              text + ": not an SQLite database (esf databases are SQLite)");
    EXPECT_EQ(io_error_of([&] { Database db(text, OpenMode::kWrite); }),
              text + ": not an SQLite database (esf databases are SQLite)");

    const std::string empty = file("empty.sqlite");
    std::ofstream(empty).flush();
    EXPECT_EQ(io_error_of([&] { Database db(empty); }),
              empty + ": empty file, not an esf database");

    EXPECT_EQ(io_error_of([&] { Database db(dir_.string()); }), dir_.string() + ": is a directory");
}

TEST_F(DatabaseTest, TruncatedDatabaseNamesTheFile) {
    const std::string path = file("db.sqlite");
    {
        Database db(path, OpenMode::kWrite);
        db.add_descriptor_kind(kEsf);
        for (int i = 0; i < 8; ++i)
            db.write_model(make_model("mug", indexed("m", i), 1.0f, 10), "esf");
    }
    const auto size = fs::file_size(path);
    fs::resize_file(path, size / 2);
    EXPECT_CONTAINS(io_error_of([&] { Database db(path); }),
                    (path + ": truncated SQLite database"));
    fs::resize_file(path, 50);
    EXPECT_CONTAINS(io_error_of([&] { Database db(path); }),
                    (path + ": truncated SQLite database (50 bytes, shorter than its header)"));
}

TEST_F(DatabaseTest, OtherSchemasAreRejected) {
    const std::string other = file("other.sqlite");
    raw_sql(other, "CREATE TABLE people(name TEXT);");
    EXPECT_EQ(io_error_of([&] { Database db(other); }),
              other + ": not an esf database (SQLite application id 0)");
    const auto read_bytes = [](const std::string& p) {
        std::ifstream in(p, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    const std::string before = read_bytes(other);
    EXPECT_EQ(io_error_of([&] { Database db(other, OpenMode::kWrite); }),
              other + ": not an esf database (SQLite application id 0)");
    EXPECT_EQ(read_bytes(other), before);  // a file that is not ours is left as it was
    EXPECT_FALSE(fs::exists(other + "-wal"));

    const std::string blank = file("blank.sqlite");
    raw_sql(blank, "PRAGMA user_version = 0;");
    EXPECT_EQ(io_error_of([&] { Database db(blank); }),
              blank + ": empty SQLite database, not an esf database");

    const std::string newer = file("newer.sqlite");
    Database(newer, OpenMode::kWrite);
    raw_sql(newer, "PRAGMA user_version = 99;");
    EXPECT_EQ(io_error_of([&] { Database db(newer); }),
              newer + ": esf database schema version 99, this version of esf reads version 1");

    const std::string damaged = file("damaged.sqlite");
    Database(damaged, OpenMode::kWrite);
    raw_sql(damaged, "DROP TABLE weights;");
    EXPECT_EQ(io_error_of([&] { Database db(damaged); }),
              damaged + ": corrupt esf database: table 'weights' is missing");
}

TEST_F(DatabaseTest, CorruptRowsAreReportedNotReadPastTheirEnd) {
    const std::string path = file("db.sqlite");
    {
        Database db(path, OpenMode::kWrite);
        db.add_descriptor_kind(kEsf);
        db.write_model(make_model("mug", "a", 1.0f), "esf");
    }
    raw_sql(path,
            "UPDATE descriptors SET data = x'00010203' WHERE signature = 0 AND "
            "view_id = (SELECT min(id) FROM views);");
    const Database db(path);
    EXPECT_EQ(io_error_of([&] { db.load_descriptors(); }),
              path + ": corrupt database: a descriptor holds 4 bytes, expected 2560");
}

TEST_F(DatabaseTest, DamagedPagesSurfaceAsIoError) {
    const std::string path = file("db.sqlite");
    {
        Database db(path, OpenMode::kWrite);
        db.add_descriptor_kind(kEsf);
        for (int i = 0; i < 4; ++i)
            db.write_model(make_model("mug", indexed("m", i), 1.0f, 20), "esf");
    }
    // Overwrite every page after the first two with garbage (the header stays valid).
    {
        std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(8192);
        const std::string junk(static_cast<std::size_t>(fs::file_size(path)) - 8192, '\x5a');
        f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
    }
    const std::string message = io_error_of([&] {
        Database db(path);
        db.summary();
        db.load_descriptors();
    });
    EXPECT_CONTAINS(message, (path + ": "));
    EXPECT_NE(message, "(no IoError)");
}

// A writer killed at a random moment (SIGKILL, no clean-up) leaves only complete models; the
// next reader sees a consistent database and the next writer can continue.
TEST_F(DatabaseTest, KilledWriterLeavesOnlyCompleteModels) {
    const std::string path = file("db.sqlite");
    {
        Database db(path, OpenMode::kWrite);
        db.add_descriptor_kind(kEsf);
    }
    constexpr int kViews = 40;
    for (int delay_ms : {30, 120}) {
        const pid_t child = fork();
        ASSERT_GE(child, 0);
        if (child == 0) {
            try {
                Database db(path, OpenMode::kWrite);
                for (int i = 0;; ++i)
                    db.write_model(
                        make_model("mug", "k" + std::to_string(delay_ms) + "_" + std::to_string(i),
                                   static_cast<float>(i), kViews),
                        "esf");
            } catch (...) {
            }
            _exit(1);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
        kill(child, SIGKILL);
        int status = 0;
        waitpid(child, &status, 0);
        ASSERT_TRUE(WIFSIGNALED(status));

        // A reader first (it must cope with the writer's leftover journal), then a writer.
        {
            const Database reader(path);
            for (const auto& m : reader.models()) {
                EXPECT_EQ(m.status, ModelStatus::kComplete);
                EXPECT_EQ(m.views, static_cast<std::size_t>(kViews)) << m.name;
            }
        }
        Database writer(path, OpenMode::kWrite);
        const auto summary = writer.summary();
        EXPECT_EQ(summary.views, summary.models * kViews);
        EXPECT_EQ(writer.load_descriptors().rows(), summary.views);
        writer.write_model(make_model("box", indexed("after", delay_ms), 1.0f, kViews), "esf");
    }
    const Database db(path);
    EXPECT_EQ(db.summary().categories.at(0).models, 2u);
}

// A writer killed inside a transaction after SQLite spilled changed pages into the file leaves a
// hot journal: a read-only open must still see the last committed state, and create nothing.
TEST_F(DatabaseTest, ReadOnlyOpenAfterAKilledTransaction) {
    const std::string path = file("db.sqlite");
    {
        Database db(path, OpenMode::kWrite);
        db.add_descriptor_kind(kEsf);
        for (int i = 0; i < 3; ++i)
            db.write_model(make_model("mug", indexed("m", i), 1.0f, 20), "esf");
    }
    int ready[2];
    ASSERT_EQ(pipe(ready), 0);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        sqlite3* db = nullptr;
        sqlite3_open(path.c_str(), &db);
        sqlite3_exec(db,
                     "PRAGMA cache_size = 1; BEGIN IMMEDIATE;"
                     "UPDATE descriptors SET data = zeroblob(2560);"
                     "DELETE FROM models WHERE name = 'm0';",
                     nullptr, nullptr, nullptr);
        const char byte = 1;
        if (write(ready[1], &byte, 1) != 1) _exit(1);
        for (;;) pause();
    }
    char byte = 0;
    ASSERT_EQ(read(ready[0], &byte, 1), 1);
    kill(child, SIGKILL);
    waitpid(child, nullptr, 0);
    close(ready[0]);
    close(ready[1]);
    ASSERT_TRUE(fs::exists(path + "-journal"));

    const Database reader(path);
    EXPECT_EQ(reader.summary().models, 3u);
    EXPECT_EQ(reader.views("mug", "m1").at(5).descriptors, make_view(5, 1.0f).descriptors);
}

TEST_F(DatabaseTest, MovedDatabaseKeepsWorking) {
    Database a(file("db.sqlite"), OpenMode::kWrite);
    a.add_descriptor_kind(kEsf);
    Database b = std::move(a);
    b.write_model(make_model("mug", "a", 1.0f), "esf");
    EXPECT_EQ(b.summary().models, 1u);
}

/// A small hand-made surface: four points on a unit square, normals +z.
ModelSurface square_surface(double scale) {
    ModelSurface s;
    s.scale = scale;
    s.diameter = 0.3;
    s.points = {{0.f, 0.f, 0.f}, {0.1f, 0.f, 0.f}, {0.f, 0.1f, 0.f}, {0.1f, 0.1f, 0.f}};
    s.normals.assign(4, Eigen::Vector3f::UnitZ());
    return s;
}

TEST_F(DatabaseTest, StoresEachModelsSurfaceAndReadsItBackExactly) {
    const std::string path = file("s.db");
    {
        Database db(path, OpenMode::kWrite);
        db.add_descriptor_kind(kEsf);
        ModelEntry with = make_model("mug", "a", 1.0f);
        with.surface = square_surface(with.scale);
        db.write_model(with, "esf");
        db.write_model(make_model("mug", "b", 2.0f), "esf");
    }
    const Database db(path);
    const std::optional<ModelSurface> got = db.model_surface("mug", "a");
    ASSERT_TRUE(got.has_value());
    EXPECT_EQ(*got, square_surface(1.5));
    EXPECT_FALSE(db.model_surface("mug", "b").has_value());       // trained without one
    EXPECT_FALSE(db.model_surface("mug", "absent").has_value());  // no such model
    EXPECT_EQ(db.summary().surfaces, 1u);
    {
        // Replacing the model replaces (here: removes) its surface.
        Database w(path, OpenMode::kWrite);
        w.write_model(make_model("mug", "a", 3.0f), "esf");
    }
    EXPECT_FALSE(Database(path).model_surface("mug", "a").has_value());
    EXPECT_EQ(Database(path).summary().surfaces, 0u);
}

TEST_F(DatabaseTest, RefusesABadSurfaceAndReportsACorruptStoredOne) {
    const std::string path = file("s.db");
    Database db(path, OpenMode::kWrite);
    db.add_descriptor_kind(kEsf);
    ModelEntry m = make_model("mug", "a", 1.0f);
    m.surface = square_surface(2.0);  // not the model's scale (1.5)
    EXPECT_NE(invalid_argument_of([&] { db.write_model(m, "esf"); }).find("scale"),
              std::string::npos);
    m.surface = square_surface(m.scale);
    m.surface->normals.pop_back();
    EXPECT_NE(invalid_argument_of([&] { db.write_model(m, "esf"); }).find("3 normals for 4"),
              std::string::npos);
    m.surface = square_surface(m.scale);
    m.surface->points[2].x() = std::numeric_limits<float>::quiet_NaN();
    EXPECT_NE(invalid_argument_of([&] { db.write_model(m, "esf"); }).find("point 2"),
              std::string::npos);
    ModelEntry failed = make_model("mug", "f", 1.0f, 0);
    failed.error = "did not load";
    failed.surface = square_surface(failed.scale);
    EXPECT_NE(invalid_argument_of([&] { db.write_model(failed, "esf"); }).find("failed"),
              std::string::npos);
    EXPECT_FALSE(db.model_status("mug", "a").has_value());  // nothing written

    m.surface = square_surface(m.scale);
    db.write_model(m, "esf");
    raw_sql(path, "UPDATE model_surfaces SET points = x'00000000'");  // one float: not x y z
    std::string error = io_error_of([&] { (void)Database(path).model_surface("mug", "a"); });
    EXPECT_NE(error.find(path), std::string::npos) << error;
    EXPECT_NE(error.find("corrupt surface points"), std::string::npos) << error;
    raw_sql(path, "UPDATE model_surfaces SET points = normals, diameter = -1");
    error = io_error_of([&] { (void)Database(path).model_surface("mug", "a"); });
    EXPECT_NE(error.find("diameter"), std::string::npos) << error;
    EXPECT_NE(error.find("mug/a"), std::string::npos) << error;
}

TEST_F(DatabaseTest, AFileWithoutTheSurfaceTableReadsAsHavingNoSurfaces) {
    const std::string path = file("old.db");
    {
        Database db(path, OpenMode::kWrite);
        db.add_descriptor_kind(kEsf);
        db.write_model(make_model("mug", "a", 1.0f), "esf");
    }
    raw_sql(path, "DROP TABLE model_surfaces");  // as files written before surfaces were stored
    const Database db(path);
    EXPECT_FALSE(db.model_surface("mug", "a").has_value());
    EXPECT_EQ(db.summary().surfaces, 0u);
    EXPECT_EQ(db.summary().models, 1u);
}

}  // namespace
}  // namespace esf
