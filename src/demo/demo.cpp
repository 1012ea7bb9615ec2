#include "esf/demo/demo.hpp"

#include <stdlib.h>  // mkdtemp

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "core/elapsed_time.hpp"
#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "esf/render/render.hpp"
#include "esf/render/sensor_model.hpp"
#include "esf/render/view_sphere.hpp"
#include "esf/shapes/shape_generator.hpp"
#include "esf/training/training.hpp"

namespace esf {

namespace {

/// Camera distance of the demo's training and query views (metres).
constexpr double kDemoCameraDistance = 0.8;

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Keys of the demo's own random streams (PixelRandom's "view" argument), apart from the
// renderer's noise keys.
constexpr std::uint64_t kQueryDirectionKey = 0x51554552'59000001ull;  // "QUERY"
constexpr std::uint64_t kSceneLayoutKey = 0x5343454e'45000001ull;     // "SCENE"
// Noise keys of the query views: past every view sphere index, so that a query view never
// shares its sensor noise with a training view.
constexpr std::uint64_t kQueryNoiseKeyBase = std::uint64_t{1} << 32;
constexpr std::size_t kTopN = 10;       // the 10-NN column
constexpr double kSceneGap = 0.08;      // metres between the footprints of two objects
constexpr double kTableHalfSize = 0.6;  // metres
constexpr double kSceneMaxDepth = 4.0;  // metres, the Kinect's range

using detail::seconds_since;

void validate_options(const DemoOptions& o) {
    auto fail = [](const std::string& what) { throw std::invalid_argument("demo: " + what); };
    if (o.per_class < 1 || o.per_class > 1000)
        fail("per_class must be in [1, 1000], got " + std::to_string(o.per_class));
    if (o.level < 0 || o.level > kMaxViewSphereLevel)
        fail("level must be in [0, " + std::to_string(kMaxViewSphereLevel) + "], got " +
             std::to_string(o.level));
    if (o.query_models < 1 || o.query_models > 1000)
        fail("query_models must be in [1, 1000], got " + std::to_string(o.query_models));
    if (o.query_views < 1 || o.query_views > 10000)
        fail("query_views must be in [1, 10000], got " + std::to_string(o.query_views));
    const int categories = static_cast<int>(generated_categories().size());
    if (o.scene_objects < 0 || o.scene_objects > categories)
        fail("scene_objects must be in [0, " + std::to_string(categories) + "], got " +
             std::to_string(o.scene_objects));
    if (!(o.scene_distance >= 0.5 && o.scene_distance <= 3.0))
        fail("scene_distance must be in [0.5, 3] m, got " + std::to_string(o.scene_distance));
    if (!(o.scene_elevation_deg >= 10.0 && o.scene_elevation_deg <= 80.0))
        fail("scene_elevation_deg must be in [10, 80], got " +
             std::to_string(o.scene_elevation_deg));
    if (o.threads < 0) fail("threads must be >= 0, got " + std::to_string(o.threads));
}

/// The work folder; a temporary one is removed when the demo ends, also by an exception.
class WorkDir {
  public:
    explicit WorkDir(const std::string& requested) {
        if (!requested.empty()) {
            path_ = requested;
            std::error_code ec;
            fs::create_directories(path_, ec);
            if (ec || !fs::is_directory(path_))
                throw IoError(file_message(
                    requested, 0,
                    "cannot create the work folder: " + (ec ? ec.message() : "not a folder")));
            return;
        }
        std::error_code ec;
        const fs::path tmp = fs::temp_directory_path(ec);
        if (ec) throw IoError("demo: no temporary directory: " + ec.message());
        std::string pattern = (tmp / "esf-demo-XXXXXX").string();
        if (::mkdtemp(pattern.data()) == nullptr)
            throw IoError(file_message(pattern, 0, "cannot create a temporary folder"));
        path_ = pattern;
        owned_ = true;
    }
    ~WorkDir() { remove(); }
    WorkDir(const WorkDir&) = delete;
    WorkDir& operator=(const WorkDir&) = delete;

    const fs::path& path() const { return path_; }
    /// Removes a temporary folder; returns whether it did.
    bool remove() {
        if (!owned_) return false;
        owned_ = false;
        std::error_code ec;
        fs::remove_all(path_, ec);
        return !ec;
    }

  private:
    fs::path path_;
    bool owned_ = false;
};

/// A direction uniform on the unit sphere.
Eigen::Vector3d random_direction(PixelRandom& random) {
    const double z = 2.0 * random.uniform() - 1.0;
    const double phi = 2.0 * std::numbers::pi * random.uniform();
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {s * std::cos(phi), s * std::sin(phi), z};
}

struct HeldOut {
    std::string category;
    std::string name;
    Mesh mesh;
};

/// The held-out models: indices per_class .. per_class + query_models - 1 of each category.
std::vector<HeldOut> held_out_models(const std::vector<std::string>& categories,
                                     const DemoOptions& o) {
    std::vector<HeldOut> models(categories.size() * static_cast<std::size_t>(o.query_models));
    parallel_for(models.size(), o.threads, [&](std::size_t i) {
        const std::string& category = categories[i / static_cast<std::size_t>(o.query_models)];
        const int index =
            o.per_class + static_cast<int>(i % static_cast<std::size_t>(o.query_models));
        models[i] = {category, generated_model_name(category, index),
                     generate_shape(category, o.seed, index)};
    });
    return models;
}

/// Renders query_views random views of a held-out model with the training's sensor model.
std::vector<Points> render_queries(const HeldOut& model, const RenderOptions& training_render,
                                   const DemoOptions& o) {
    RenderOptions render = training_render;
    render.seed = model_seed(o.seed, model.category, model.name);
    render.threads = 1;
    const MeshRenderer renderer(model.mesh, render);
    const Eigen::Vector3d centre = renderer.centre() * renderer.scale();
    std::vector<Points> views(static_cast<std::size_t>(o.query_views));
    parallel_for(views.size(), o.threads, [&](std::size_t v) {
        PixelRandom random(render.seed, kQueryDirectionKey, v);
        const Eigen::Vector3d eye = centre + renderer.camera_distance() * random_direction(random);
        views[v] = renderer.render_pose(look_at(eye, centre), kQueryNoiseKeyBase + v);
    });
    return views;
}

DemoQuery query_result(const HeldOut& model, int view, std::size_t points,
                       const CloudClassification& c) {
    DemoQuery q;
    q.category = model.category;
    q.model = model.name;
    q.view = view;
    q.points = points;
    q.error = c.error;
    if (!c.ok()) return q;
    const Classification& k = c.classification;
    if (k.neighbours.empty()) {
        q.error = "no neighbours";
        return q;
    }
    q.nearest_class = k.neighbours.front().class_name;
    q.vote_class = k.class_name;
    q.confidence = k.confidence;
    for (std::size_t i = 0; i < std::min(kTopN, k.neighbours.size()) && q.rank == 0; ++i)
        if (k.neighbours[i].class_name == q.category) q.rank = i + 1;
    return q;
}

QueryOutcome outcome(const DemoQuery& q, const CloudClassification& c) {
    QueryOutcome o;
    o.file = q.category + "/" + q.model + "#" + std::to_string(q.view);
    o.true_class = q.category;
    o.error = q.error;
    if (q.error.empty())
        for (const NeighbourView& n : c.classification.neighbours)
            o.neighbours.push_back({n.class_name, n.distance});
    return o;
}

double rate(std::size_t hits, std::size_t total) {
    return total ? static_cast<double>(hits) / static_cast<double>(total) : 0.0;
}

/// A model of the scene with its yaw applied, and its footprint on the table.
struct Placement {
    std::size_t model = 0;  ///< index into the held-out models
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d lower = Eigen::Vector3d::Zero();  ///< rotated bounding box
    Eigen::Vector3d upper = Eigen::Vector3d::Zero();
    double yaw = 0.0;
};

/// Places the models in two rows on the table, the taller ones at the back, footprints
/// kSceneGap apart, each row centred on x = 0; returns their model -> world transforms.
std::vector<Eigen::Isometry3d> layout(const std::vector<Placement>& items) {
    std::vector<std::size_t> order(items.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return items[a].upper.z() - items[a].lower.z() > items[b].upper.z() - items[b].lower.z();
    });
    const std::size_t back = (order.size() + 1) / 2;
    std::vector<Eigen::Isometry3d> poses(items.size(), Eigen::Isometry3d::Identity());
    for (int row = 0; row < 2; ++row) {
        const std::size_t first = row == 0 ? 0 : back, last = row == 0 ? back : order.size();
        if (first == last) continue;
        double width = kSceneGap * static_cast<double>(last - first - 1), depth = 0.0;
        for (std::size_t j = first; j < last; ++j) {
            const Placement& p = items[order[j]];
            width += p.upper.x() - p.lower.x();
            depth = std::max(depth, p.upper.y() - p.lower.y());
        }
        const double y = (row == 0 ? 1.0 : -1.0) * (0.5 * kSceneGap + 0.5 * depth);
        double x = -0.5 * width;
        for (std::size_t j = first; j < last; ++j) {
            const Placement& p = items[order[j]];
            const double w = p.upper.x() - p.lower.x();
            const Eigen::Vector3d centre = 0.5 * (p.lower + p.upper);
            Eigen::Isometry3d& pose = poses[order[j]];
            pose.linear() = p.rotation;
            pose.translation() =
                Eigen::Vector3d(x + 0.5 * w - centre.x(), y - centre.y(), -p.lower.z());
            x += w + kSceneGap;
        }
    }
    return poses;
}

/// Composes the table scene of held-out models of different categories, renders it, runs the
/// scene pipeline and matches what it found to what was placed.
DemoScene run_scene(const std::vector<HeldOut>& models, const std::vector<std::string>& categories,
                    const Recognizer& recognizer, const DemoOptions& o) {
    DemoScene scene;
    // Categories: a seeded Fisher-Yates shuffle; each its first held-out model.
    std::vector<std::size_t> pick(categories.size());
    for (std::size_t i = 0; i < pick.size(); ++i) pick[i] = i;
    PixelRandom random(o.seed, kSceneLayoutKey, 0);
    for (std::size_t i = pick.size(); i > 1; --i) {
        const auto j = static_cast<std::size_t>(random.uniform() * static_cast<double>(i));
        std::swap(pick[i - 1], pick[std::min(j, i - 1)]);
    }
    pick.resize(static_cast<std::size_t>(o.scene_objects));
    std::vector<Placement> items(pick.size());
    for (std::size_t i = 0; i < pick.size(); ++i) {
        Placement& p = items[i];
        p.model = pick[i] * static_cast<std::size_t>(o.query_models);
        p.yaw = 2.0 * std::numbers::pi * random.uniform();
        p.rotation = Eigen::AngleAxisd(p.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        p.lower = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
        p.upper = -p.lower;
        for (const Eigen::Vector3f& v : models[p.model].mesh.vertices) {
            const Eigen::Vector3d q = p.rotation * v.cast<double>();
            p.lower = p.lower.cwiseMin(q);
            p.upper = p.upper.cwiseMax(q);
        }
    }
    const std::vector<Eigen::Isometry3d> poses = layout(items);

    std::vector<SceneObject> objects(items.size());
    for (std::size_t i = 0; i < items.size(); ++i) {
        const HeldOut& m = models[items[i].model];
        objects[i] = {&m.mesh, poses[i]};
        DemoPlacedObject placed;
        placed.category = m.category;
        placed.model = m.name;
        placed.position =
            (poses[i].translation() +
             poses[i].linear() * (0.5 * (m.mesh.min_corner() + m.mesh.max_corner())).cast<double>())
                .cast<float>();
        placed.position.z() = 0.0f;
        placed.yaw_deg = static_cast<float>(items[i].yaw * 180.0 / std::numbers::pi);
        placed.extent = m.mesh.max_corner() - m.mesh.min_corner();
        scene.placed.push_back(std::move(placed));
    }

    // The camera looks at the table centre from scene_distance, scene_elevation_deg above it.
    const double elevation = o.scene_elevation_deg * std::numbers::pi / 180.0;
    const Eigen::Vector3d target(0.0, 0.0, 0.0);
    const Eigen::Vector3d eye =
        target + o.scene_distance * Eigen::Vector3d(0.0, -std::cos(elevation), std::sin(elevation));
    scene.world_to_camera = look_at(eye, target);
    SceneOptions render;
    render.noise = SensorNoise::kKinect;
    render.seed = model_seed(o.seed, "demo", "scene");
    render.table_plane = true;
    render.table_half_size = kTableHalfSize;
    render.max_depth = kSceneMaxDepth;
    render.threads = o.threads;
    scene.cloud = render_scene(objects, scene.world_to_camera, render);

    // What each placed object shows.
    std::vector<Eigen::Vector3d> sums(items.size(), Eigen::Vector3d::Zero());
    for (std::size_t i = 0; i < scene.cloud.points.size(); ++i) {
        const std::uint32_t label = scene.cloud.labels[i];
        if (label < kSceneLabelFirstObject) continue;
        const std::size_t object = label - kSceneLabelFirstObject;
        if (object >= items.size() || !scene.cloud.points[i].allFinite()) continue;
        ++scene.placed[object].visible_points;
        sums[object] += scene.cloud.points[i].cast<double>();
    }
    for (std::size_t i = 0; i < items.size(); ++i) {
        const std::size_t n = scene.placed[i].visible_points;
        scene.placed[i].visible_centroid =
            n ? Eigen::Vector3f((sums[i] / static_cast<double>(n)).cast<float>())
              : Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
    }

    // The demo's objects stand apart, and its generated hammers, cars and mugs have concave
    // joints that convexity grouping cuts (as LCCP does): Euclidean clustering.
    SegmentationOptions segmentation;
    segmentation.grouping = Grouping::kEuclidean;
    segmentation.seed = o.seed;
    segmentation.threads = o.threads;
    scene.recognition = recognizer.recognize_scene(scene.cloud, segmentation);

    // Match: the placed object most of a cluster's pixels show.
    scene.found.resize(scene.recognition.objects.size());
    for (std::size_t c = 0; c < scene.recognition.objects.size(); ++c) {
        const RecognizedObject& object = scene.recognition.objects[c];
        std::vector<std::size_t> votes(items.size(), 0);
        for (const std::uint32_t index : object.cluster.indices) {
            const std::uint32_t label = scene.cloud.labels[index];
            if (label >= kSceneLabelFirstObject && label - kSceneLabelFirstObject < items.size())
                ++votes[label - kSceneLabelFirstObject];
        }
        const auto best = std::max_element(votes.begin(), votes.end());
        DemoFoundObject& found = scene.found[c];
        if (best == votes.end() || *best == 0) continue;
        found.placed = static_cast<int>(best - votes.begin());
        found.label_share = rate(*best, object.cluster.indices.size());
        found.correct = object.classified() &&
                        object.classification.class_name ==
                            scene.placed[static_cast<std::size_t>(found.placed)].category;
        // Clusters come largest first: the first one showing an object is its match.
        DemoPlacedObject& placed = scene.placed[static_cast<std::size_t>(found.placed)];
        if (placed.found_as < 0) {
            placed.found_as = static_cast<int>(c);
            ++scene.found_placed;
            scene.correct += found.correct ? 1 : 0;
        }
    }
    return scene;
}

using ReportFn = std::function<void(DemoStage, std::size_t, std::size_t)>;

/// Steps 3 and 4: the held-out queries (Table I) and the scene, with the database's recogniser.
void recognise(DemoResult& r, const RenderOptions& training_render, const DemoOptions& options,
               const ReportFn& report) {
    auto t = Clock::now();
    RecognizerOptions recognizer_options;
    recognizer_options.k = kTopN;
    recognizer_options.threads = options.threads;
    const Recognizer recognizer(r.database, recognizer_options);
    r.database_views = recognizer.info().views;
    const std::vector<HeldOut> models = held_out_models(r.categories, options);
    const std::size_t query_total = models.size() * static_cast<std::size_t>(options.query_views);
    report(DemoStage::kQuery, 0, query_total);
    std::vector<QueryOutcome> outcomes;
    for (const HeldOut& model : models) {
        const std::vector<Points> views = render_queries(model, training_render, options);
        const std::vector<CloudClassification> classes = recognizer.classify_batch(views);
        for (std::size_t v = 0; v < views.size(); ++v) {
            r.queries.push_back(
                query_result(model, static_cast<int>(v), views[v].size(), classes[v]));
            outcomes.push_back(outcome(r.queries.back(), classes[v]));
        }
        report(DemoStage::kQuery, r.queries.size(), query_total);
    }
    r.evaluation = evaluate(outcomes, kTopN, r.categories);
    r.evaluation.mode = "held-out generated models";
    r.evaluation.database = r.database;
    r.evaluation.test_set = std::to_string(models.size()) + " held-out models x " +
                            std::to_string(options.query_views) + " random Kinect views";
    r.evaluation.descriptor = recognizer.info().setup.kind.name;
    r.evaluation.weighted = recognizer.info().weighted;
    r.evaluation.threads = resolve_threads(options.threads);
    r.seconds.query = seconds_since(t);

    t = Clock::now();
    if (options.scene_objects > 0) {
        report(DemoStage::kScene, 0, 1);
        r.scene = run_scene(models, r.categories, recognizer, options);
        report(DemoStage::kScene, 1, 1);
    }
    r.seconds.scene = seconds_since(t);
}

}  // namespace

DemoResult run_demo(const DemoOptions& options) {
    validate_options(options);
    const auto start = Clock::now();
    DemoStage current = DemoStage::kGenerate;
    auto stage_start = Clock::now();
    std::size_t views = 0;
    const ReportFn report = [&](DemoStage stage, std::size_t done, std::size_t total) {
        if (stage != current || done == 0) {
            current = stage;
            stage_start = Clock::now();
        }
        if (options.progress)
            options.progress(DemoProgress{stage, done, total,
                                          stage == DemoStage::kTrain ? views : 0,
                                          seconds_since(stage_start)});
    };
    DemoResult r;
    r.seed = options.seed;
    r.categories = generated_categories();
    r.per_class = options.per_class;
    r.level = options.level;
    r.query_models = options.query_models;
    r.query_views = options.query_views;

    WorkDir work(options.work_dir);
    r.work_dir = work.path().string();
    const std::string key =
        "seed" + std::to_string(options.seed) + "_n" + std::to_string(options.per_class);
    r.models_dir = (work.path() / ("train_" + key)).string();
    r.database =
        (work.path() / ("demo_" + key + "_level" + std::to_string(options.level) + ".db")).string();

    // 1. Training models.
    auto t = Clock::now();
    GeneratorOptions generator;
    generator.per_class = options.per_class;
    generator.seed = options.seed;
    generator.threads = options.threads;
    const std::size_t model_count =
        r.categories.size() * static_cast<std::size_t>(options.per_class);
    report(DemoStage::kGenerate, 0, model_count);
    write_dataset(r.models_dir, generator, [&](std::size_t done, std::size_t total) {
        report(DemoStage::kGenerate, done, total);
    });
    r.seconds.generate = seconds_since(t);

    // 2. The database (closed before the recogniser opens it).
    t = Clock::now();
    report(DemoStage::kTrain, 0, model_count);
    TrainingOptions training;
    // The demo's queries come from the whole view sphere at one distance (render_query_views),
    // so it trains on the whole sphere at that distance.
    training.render.level = options.level;
    training.render.distance = kDemoCameraDistance;
    training.render.max_distance.reset();
    training.render.min_elevation = -90.0;
    training.render.noise = SensorNoise::kKinect;
    training.seed = options.seed;
    training.threads = options.threads;
    training.use_catalog = false;
    training.progress = [&](const TrainingProgress& p) {
        views = p.views;
        report(DemoStage::kTrain, p.models_done, p.models_total);
    };
    {
        Database database(r.database, OpenMode::kWrite);
        const TrainingResult trained = train(r.models_dir, database, training);
        r.train_models = trained.models_total;
        r.train_models_existing = trained.models_existing;
        r.train_views = trained.views;
        r.train_views_skipped = trained.views_skipped;
        if (trained.models_failed)
            throw std::runtime_error(
                "demo: " + std::to_string(trained.models_failed) +
                " generated models failed to train, the first: " + trained.failures.front().model +
                ": " + trained.failures.front().error);
    }
    r.seconds.train = seconds_since(t);

    // 3. Held-out queries and Table I; 4. a table scene.
    recognise(r, training.render, options, report);
    r.work_dir_removed = work.remove();
    r.seconds.total = seconds_since(start);
    return r;
}

}  // namespace esf
