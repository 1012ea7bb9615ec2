// The `esf` Python module (esf._esf): the C++ core with numpy arrays in and out. Thin: every
// function converts its arguments (python/src/points.hpp), releases the GIL, calls the library
// and converts the result back. Errors: std::invalid_argument -> ValueError, esf::IoError ->
// OSError (FileNotFoundError when the named file does not exist), with the library's messages.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdint>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/evaluation/evaluation.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/render/render.hpp"
#include "esf/render/sensor_model.hpp"
#include "esf/report/report.hpp"
#include "esf/segmentation/segmentation.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"
#include "points.hpp"

namespace esf::python {

namespace {

namespace fs = std::filesystem;

/// Thrown for an IoError about a file that does not exist: FileNotFoundError.
struct FileNotFound : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// Runs `f`; an IoError becomes FileNotFound when one of `paths` does not exist.
template <typename F>
auto with_files(std::initializer_list<const fs::path*> paths, F&& f) {
    try {
        return f();
    } catch (const IoError& e) {
        std::error_code ec;
        for (const fs::path* p : paths)
            if (!p->empty() && !fs::exists(*p, ec)) throw FileNotFound(e.what());
        throw;
    }
}

// ---- descriptors ----------------------------------------------------------------------------

/// Estimator pools by options, so that repeated describe() calls reuse their workspaces (their
/// set-up is about a quarter of a description). A pool is thread-safe; the map is locked, and a
/// caller keeps its pool alive while the map forgets it.
class PoolCache {
  public:
    std::shared_ptr<const EsfEstimatorPool> get(const EsfOptions& options) {
        const Key key{options.samples, options.grid_size, options.seed,
                      static_cast<int>(options.sampler)};
        std::lock_guard<std::mutex> lock(mutex_);
        auto it = pools_.find(key);
        if (it != pools_.end()) return it->second;
        if (pools_.size() >= kMaxPools) pools_.clear();
        auto pool = std::make_shared<const EsfEstimatorPool>(options);
        pools_.emplace(key, pool);
        return pool;
    }

  private:
    using Key = std::tuple<int, int, std::uint64_t, int>;
    static constexpr std::size_t kMaxPools = 8;
    std::mutex mutex_;
    std::map<Key, std::shared_ptr<const EsfEstimatorPool>> pools_;
};

PoolCache& pool_cache() {
    static PoolCache cache;
    return cache;
}

EsfOptions esf_options(int samples, std::uint64_t seed, const std::string& sampler, int grid) {
    EsfOptions options;
    options.samples = samples;
    options.seed = seed;
    options.sampler = parse_esf_sampler(sampler);
    options.grid_size = grid;
    return options;
}

py::array_t<float> descriptor_array(const EsfDescriptor& d) {
    return py::array_t<float>(static_cast<py::ssize_t>(d.size()), d.data());
}

py::array_t<float> describe(const py::object& points, int samples, std::uint64_t seed,
                            const std::string& sampler, int grid) {
    const PointsArg arg = points_arg(points);
    const EsfOptions options = esf_options(samples, seed, sampler, grid);
    EsfResult result;
    {
        py::gil_scoped_release release;
        const std::shared_ptr<const EsfEstimatorPool> pool = pool_cache().get(options);
        result = pool->compute(arg.points);
    }
    return descriptor_array(result.descriptor);
}

py::array_t<float> describe_batch(const py::sequence& clouds, int samples, std::uint64_t seed,
                                  const std::string& sampler, int grid, int threads) {
    std::vector<PointsArg> args;
    args.reserve(clouds.size());
    for (std::size_t i = 0; i < clouds.size(); ++i)
        args.push_back(points_arg(clouds[i], "clouds[" + std::to_string(i) + "]"));
    const EsfOptions options = esf_options(samples, seed, sampler, grid);
    py::array_t<float> out({static_cast<py::ssize_t>(args.size()), py::ssize_t{kEsfSize}});
    float* data = out.mutable_data();
    std::vector<std::string> errors(args.size());
    {
        py::gil_scoped_release release;
        resolve_threads(threads);  // rejects negative counts
        const std::shared_ptr<const EsfEstimatorPool> pool = pool_cache().get(options);
        parallel_for(args.size(), threads, [&](std::size_t i) {
            try {
                const EsfResult r = pool->compute(args[i].points);
                std::copy(r.descriptor.begin(), r.descriptor.end(), data + i * kEsfSize);
            } catch (const std::invalid_argument& e) {
                errors[i] = e.what();
            }
        });
    }
    for (std::size_t i = 0; i < errors.size(); ++i)
        if (!errors[i].empty())
            throw std::invalid_argument("clouds[" + std::to_string(i) + "]: " + errors[i]);
    return out;
}

// ---- clouds ---------------------------------------------------------------------------------

py::array_t<float> read_cloud_py(const fs::path& path, bool organized) {
    PointCloud cloud;
    {
        py::gil_scoped_release release;
        cloud = with_files({&path}, [&] { return read_cloud(path.string()); });
    }
    if (organized) {
        const std::size_t height = cloud.height, width = cloud.points.size() / height;
        return organised_array(std::move(cloud.points), height, width);
    }
    return points_array(drop_non_finite(cloud.points).points);
}

void write_cloud_py(const fs::path& path, const py::object& points, const std::string& encoding) {
    if (cloud_format_from_path(path.string()) != CloudFormat::kPcd)
        throw std::invalid_argument(path.string() + ": write_cloud writes PCD files (.pcd)");
    PcdEncoding e = PcdEncoding::kBinary;
    if (encoding == "ascii")
        e = PcdEncoding::kAscii;
    else if (encoding == "binary_compressed")
        e = PcdEncoding::kBinaryCompressed;
    else if (encoding != "binary")
        throw std::invalid_argument("unknown PCD encoding '" + encoding +
                                    "' (ascii, binary or binary_compressed)");
    const PointsArg arg = points_arg(points);
    py::gil_scoped_release release;
    const PointCloud cloud = arg.cloud();
    write_pcd(path.string(), cloud, e);
}

// ---- segmentation ---------------------------------------------------------------------------

/// The segmentation options Python passes by keyword (the rest keep their defaults).
struct SegmentArgs {
    std::string grouping = "convexity";
    float plane_distance = 0.01f;
    float min_height = 0.01f;
    float max_height = 0.40f;
    float cluster_tolerance = 0.02f;
    std::size_t min_cluster_points = 100;
    std::optional<std::vector<float>> viewpoint;
    std::uint64_t seed = 0;
    int threads = 0;

    SegmentationOptions options() const {
        SegmentationOptions o;
        if (grouping == "euclidean")
            o.grouping = Grouping::kEuclidean;
        else if (grouping != "convexity")
            throw std::invalid_argument("unknown grouping '" + grouping +
                                        "' (convexity or euclidean)");
        o.plane_distance = plane_distance;
        o.min_height = min_height;
        o.max_height = max_height;
        o.cluster_tolerance = cluster_tolerance;
        o.min_cluster_points = min_cluster_points;
        if (viewpoint) {
            if (viewpoint->size() != 3)
                throw std::invalid_argument("viewpoint: expected 3 numbers, got " +
                                            std::to_string(viewpoint->size()));
            o.viewpoint = {(*viewpoint)[0], (*viewpoint)[1], (*viewpoint)[2]};
        }
        o.seed = seed;
        o.threads = threads;
        validate(o);
        return o;
    }
};

#define ESF_SEGMENT_ARGS                                                       \
    py::arg("grouping") = "convexity", py::arg("plane_distance") = 0.01f,      \
    py::arg("min_height") = 0.01f, py::arg("max_height") = 0.40f,              \
    py::arg("cluster_tolerance") = 0.02f, py::arg("min_cluster_points") = 100, \
    py::arg("viewpoint") = py::none(), py::arg("seed") = 0, py::arg("threads") = 0

SegmentationResult segment_py(const py::object& points, const SegmentArgs& args) {
    const PointsArg arg = points_arg(points);
    const SegmentationOptions options = args.options();
    py::gil_scoped_release release;
    return segment_scene(arg.cloud(), options);
}

// ---- recognition ----------------------------------------------------------------------------

Classification classify_py(const Recognizer& recognizer, const py::object& points,
                           std::optional<std::size_t> k) {
    const PointsArg arg = points_arg(points);
    if (k && *k == 0) throw std::invalid_argument("k must be >= 1");
    py::gil_scoped_release release;
    if (!k || *k == recognizer.options().k) return recognizer.classify(arg.points);
    // Another k than the recognizer's: the same search and vote with k views.
    const QueryDescriptor d = recognizer.describe(arg.points);
    if (!d.ok()) throw std::invalid_argument(d.error);
    const Classifier& classifier = recognizer.classifier();
    if (d.signatures.size() != classifier.index().dimension())
        throw std::invalid_argument(
            "k other than the Recognizer's needs a single-signature descriptor; create the "
            "Recognizer with k=" +
            std::to_string(*k));
    const KnnResult found = classifier.index().search(d.signatures, *k);
    return classify_neighbours(found.neighbours, classifier.labels());
}

std::vector<RecognizedObject> scene_py(const Recognizer& recognizer, const py::object& points,
                                       const SegmentArgs& args) {
    const PointsArg arg = points_arg(points);
    const SegmentationOptions options = args.options();
    py::gil_scoped_release release;
    return recognizer.recognize_scene(arg.cloud(), options).objects;
}

py::object evaluate_py(const fs::path& database, const fs::path& test_set, std::size_t k,
                       const std::string& descriptor, bool use_weights, int samplings,
                       int threads) {
    std::string json;
    {
        py::gil_scoped_release release;
        json = with_files({&database, &test_set}, [&] {
            const TestSet set = read_test_set(test_set.string());
            RecognizerOptions recognizer_options;
            recognizer_options.k = k;
            recognizer_options.descriptor = descriptor;
            recognizer_options.use_weights = use_weights;
            recognizer_options.query_samplings = samplings;
            recognizer_options.threads = threads;
            const Recognizer recognizer(database.string(), recognizer_options);
            EvaluationOptions options;
            options.k = k;
            options.threads = threads;
            const EvaluationReport report = evaluate_test_set(recognizer, set, options);
            if (report.samples == 0)
                throw std::invalid_argument("no sample could be evaluated (" +
                                            std::to_string(report.skipped) + " skipped, " +
                                            std::to_string(report.failed) + " failed)");
            // What `esf eval --json` prints.
            ReportOptions report_options;
            report_options.include_queries = false;
            report_options.title = "";
            return report_json(report, report_options);
        });
    }
    return py::module_::import("json").attr("loads")(json);
}

// ---- training and rendering -----------------------------------------------------------------

py::dict train_py(const fs::path& root, const fs::path& database, const std::string& descriptor,
                  int level, int samples, std::uint64_t seed, const std::string& noise,
                  std::optional<double> distance, std::optional<double> max_distance,
                  double min_elevation, double max_elevation, std::size_t min_points,
                  std::optional<fs::path> catalog, bool use_catalog, int threads,
                  std::optional<py::function> progress) {
    TrainingOptions options;
    options.render.level = level;
    options.render.noise = parse_sensor_noise(noise);
    options.render.distance = distance;
    options.render.max_distance = max_distance;
    options.render.min_elevation = min_elevation;
    options.render.max_elevation = max_elevation;
    options.descriptor = descriptor;
    options.esf.samples = samples;
    options.descriptor_options.samples = samples;
    options.seed = seed;
    options.min_points = min_points;
    options.threads = threads;
    if (catalog) options.catalog = catalog->string();
    options.use_catalog = use_catalog;
    // Runs on this thread between models: Ctrl-C (or an exception in `progress`) stops the
    // training there; the models committed so far stay and the next run resumes after them.
    options.progress = [&progress](const TrainingProgress& p) {
        py::gil_scoped_acquire acquire;
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        if (progress) (*progress)(p);
    };
    TrainingResult result;
    {
        py::gil_scoped_release release;
        result = with_files({&root}, [&] {
            find_models(root.string());  // a missing root fails before the database is created
            Database db(database.string(), OpenMode::kWrite);
            return train(root.string(), db, options);
        });
    }
    py::list failures;
    for (const TrainingFailure& f : result.failures)
        failures.append(py::dict(py::arg("model") = f.model, py::arg("error") = f.error));
    return py::dict(
        py::arg("database") = database.string(), py::arg("descriptor") = descriptor,
        py::arg("models") = result.models_total, py::arg("models_trained") = result.models_trained,
        py::arg("models_existing") = result.models_existing,
        py::arg("models_failed") = result.models_failed, py::arg("views") = result.views,
        py::arg("skipped_views") = result.views_skipped, py::arg("failures") = failures);
}

std::vector<RenderedView> render_py(const fs::path& mesh_path, int level, int width, int height,
                                    std::optional<double> fx, std::optional<double> fy,
                                    std::optional<double> cx, std::optional<double> cy, double fill,
                                    std::optional<double> distance,
                                    std::optional<double> max_distance, double min_elevation,
                                    double max_elevation, const std::string& noise,
                                    std::uint64_t seed, double scale, std::optional<double> extent,
                                    int threads) {
    RenderOptions options;
    options.level = level;
    options.camera.width = width;
    options.camera.height = height;
    options.camera.fx = fx.value_or(options.camera.fx);
    options.camera.fy = fy.value_or(options.camera.fy);
    options.camera.cx = cx.value_or((width - 1) / 2.0);
    options.camera.cy = cy.value_or((height - 1) / 2.0);
    options.fill_fraction = fill;
    options.distance = distance;
    options.max_distance = max_distance;
    options.min_elevation = min_elevation;
    options.max_elevation = max_elevation;
    options.noise = parse_sensor_noise(noise);
    options.seed = seed;
    options.scale = scale;
    options.target_extent = extent;
    options.threads = threads;
    py::gil_scoped_release release;
    const Mesh mesh = with_files({&mesh_path}, [&] { return load_mesh(mesh_path.string()); });
    return render_views(mesh, options);
}

// ---- database -------------------------------------------------------------------------------

py::object setting_object(const SettingValue& value) {
    if (const auto* i = std::get_if<std::int64_t>(&value)) return py::int_(*i);
    if (const auto* d = std::get_if<double>(&value)) return py::float_(*d);
    return py::str(std::get<std::string>(value));
}

py::dict model_dict(const ModelInfo& m) {
    return py::dict(py::arg("category") = m.category, py::arg("name") = m.name,
                    py::arg("file") = m.file, py::arg("group") = m.group,
                    py::arg("scale") = m.scale, py::arg("status") = to_string(m.status),
                    py::arg("error") = m.error, py::arg("views") = m.views,
                    py::arg("skipped_views") = m.skipped_views);
}

py::dict view_dict(const ViewEntry& v, int dimension) {
    py::object descriptors = py::none();
    if (!v.skipped()) {
        const auto rows = static_cast<py::ssize_t>(v.descriptors.size()) / dimension;
        descriptors =
            py::array_t<float>({rows, static_cast<py::ssize_t>(dimension)}, v.descriptors.data());
    }
    return py::dict(py::arg("index") = v.index, py::arg("points") = v.points,
                    py::arg("pose") = matrix_array(v.pose), py::arg("descriptors") = descriptors,
                    py::arg("skip_reason") = v.skip_reason);
}

int kind_dimension(const Database& db, const std::string& descriptor) {
    const std::vector<DescriptorKind> kinds = db.descriptor_kinds();
    for (const DescriptorKind& k : kinds)
        if (k.name == descriptor || (descriptor.empty() && kinds.size() == 1)) return k.dimension;
    return 1;  // Database::views() reports the unknown or ambiguous kind
}

// ---- exceptions -----------------------------------------------------------------------------

void translate_exception(std::exception_ptr p) {
    try {
        if (p) std::rethrow_exception(p);
    } catch (const FileNotFound& e) {
        PyErr_SetString(PyExc_FileNotFoundError, e.what());
    } catch (const IoError& e) {
        PyErr_SetString(PyExc_OSError, e.what());
    }
}

std::string classification_repr(const Classification& c) {
    return "Classification(class_name='" + c.class_name +
           "', confidence=" + std::to_string(c.confidence) + ", model='" + c.best_model +
           "', view=" + std::to_string(c.best_view) +
           ", distance=" + std::to_string(c.best_distance) + ")";
}

}  // namespace

}  // namespace esf::python

using namespace esf;          // NOLINT: the module's names read as the library's
using namespace esf::python;  // NOLINT

PYBIND11_MODULE(_esf, m) {
    m.doc() =
        "ESF (Ensemble of Shape Functions) descriptors, training on CAD models and table-scene "
        "recognition: the esf C++ library with numpy arrays in and out.";
    m.attr("__version__") = ESF_VERSION;
    m.attr("ESF_SIZE") = kEsfSize;
    py::register_exception_translator(&translate_exception);

    m.def(
        "as_points", [](const py::object& points) { return points_arg(points).array; },
        py::arg("points"),
        "The float32 array esf computes on for ``points``: ``points`` itself when it is a "
        "C-contiguous float32 (N, 3) or (H, W, 3) array (no copy), otherwise one converted "
        "copy. Accepts any array-like of numbers and objects with a ``points`` attribute (an "
        "Open3D PointCloud). Raises TypeError for non-numbers, ValueError for a wrong shape.");

    m.def("read_cloud", &read_cloud_py, py::arg("path"), py::kw_only(),
          py::arg("organized") = false,
          "Reads a point cloud (.pcd, .ply, .xyz/.txt/.pts). Returns an (N, 3) float32 array of "
          "its finite points; with ``organized=True`` an (H, W, 3) array of all points, NaN "
          "where the sensor had no return (an unorganised file gives (1, N, 3)). Raises "
          "FileNotFoundError / OSError with the reader's message.");
    m.def("write_cloud", &write_cloud_py, py::arg("path"), py::arg("points"), py::kw_only(),
          py::arg("encoding") = "binary",
          "Writes points ((N, 3), or (H, W, 3) kept organised) to a PCD file; ``encoding`` is "
          "'binary', 'ascii' or 'binary_compressed'. The file appears complete or not at all.");

    m.def("describe", &describe, py::arg("points"), py::kw_only(), py::arg("samples") = 20000,
          py::arg("seed") = 0, py::arg("sampler") = "fast", py::arg("grid") = 64,
          "The 640-bin ESF descriptor of a cloud (float32, L1-normalised): the same numbers as "
          "``esf describe`` for the same points, seed, samples and sampler ('fast' or 'pcl', "
          "bit-exact pcl::ESFEstimation). Non-finite points are dropped first. Raises ValueError "
          "for a cloud without descriptor (fewer than 3 finite points, all on one line). The "
          "GIL is released while computing.");
    m.def("describe_batch", &describe_batch, py::arg("clouds"), py::kw_only(),
          py::arg("samples") = 20000, py::arg("seed") = 0, py::arg("sampler") = "fast",
          py::arg("grid") = 64, py::arg("threads") = 0,
          "Describes many clouds in parallel (``threads``, 0 = all cores): an (M, 640) float32 "
          "array, row i = describe(clouds[i], seed=seed). Raises ValueError naming the first "
          "cloud that has no descriptor.");

    py::class_<Cluster>(m, "Cluster", "One object above the table (esf.segment).")
        .def_property_readonly(
            "points", [](const Cluster& c) { return points_array(c.points); },
            "(N, 3) float32 points of the object")
        .def_property_readonly(
            "indices",
            [](const Cluster& c) {
                return py::array_t<std::uint32_t>(static_cast<py::ssize_t>(c.indices.size()),
                                                  c.indices.data());
            },
            "indices of the points in the input (row-major for (H, W, 3) input)")
        .def_property_readonly(
            "centroid", [](const Cluster& c) { return vector_array(c.centroid); },
            "(3,) mean of the points, metres")
        .def_property_readonly(
            "size", [](const Cluster& c) { return vector_array(c.size); },
            "(3,) length, width (in the table plane) and height, metres")
        .def_property_readonly(
            "truncated", [](const Cluster& c) { return c.status != ClusterStatus::kOk; },
            "the object may be cut off by the image border or max_height")
        .def_readonly("message", &Cluster::message)
        .def("__repr__", [](const Cluster& c) {
            return "Cluster(points=" + std::to_string(c.points.size()) + ")";
        });

    py::class_<SegmentationResult>(m, "Segmentation", "The result of esf.segment.")
        .def_readonly("plane_found", &SegmentationResult::plane_found)
        .def_property_readonly(
            "plane",
            [](const SegmentationResult& s) {
                const Eigen::Vector3f& n = s.plane.normal;
                py::array_t<float> out(4);
                auto v = out.mutable_unchecked<1>();
                v(0) = n.x(), v(1) = n.y(), v(2) = n.z(), v(3) = s.plane.d;
                return out;
            },
            "(4,) a, b, c, d of the table plane ax + by + cz + d = 0, normal towards the sensor")
        .def_readonly("plane_inliers", &SegmentationResult::plane_inliers)
        .def_readonly("finite_points", &SegmentationResult::finite_points)
        .def_readonly("clusters", &SegmentationResult::clusters)
        .def_readonly("message", &SegmentationResult::message)
        .def("__repr__",
             [](const SegmentationResult& s) { return "Segmentation(" + s.message + ")"; });

    m.def(
        "segment",
        [](const py::object& points, const std::string& grouping, float plane_distance,
           float min_height, float max_height, float cluster_tolerance,
           std::size_t min_cluster_points, std::optional<std::vector<float>> viewpoint,
           std::uint64_t seed, int threads) {
            return segment_py(points,
                              {grouping, plane_distance, min_height, max_height, cluster_tolerance,
                               min_cluster_points, std::move(viewpoint), seed, threads});
        },
        py::arg("points"), py::kw_only(), ESF_SEGMENT_ARGS,
        "Segments a table scene ((H, W, 3) organised or (N, 3)): the dominant plane, and the "
        "objects above it as clusters (largest first). ``grouping`` is 'convexity' (objects "
        "part at concave creases) or 'euclidean'; lengths in metres. A scene without plane or "
        "objects is no error: see ``message``.");

    py::class_<NeighbourView>(m, "Neighbour", "One of the k nearest database views.")
        .def_readonly("class_name", &NeighbourView::class_name)
        .def_readonly("model", &NeighbourView::model_name)
        .def_readonly("view", &NeighbourView::view)
        .def_readonly("distance", &NeighbourView::distance)
        .def_property_readonly("pose", [](const NeighbourView& n) { return matrix_array(n.pose); })
        .def("__repr__", [](const NeighbourView& n) {
            return "Neighbour(class_name='" + n.class_name + "', model='" + n.model_name +
                   "', view=" + std::to_string(n.view) +
                   ", distance=" + std::to_string(n.distance) + ")";
        });

    py::class_<Classification>(m, "Classification",
                               "The vote of the k nearest views: class, confidence, and the "
                               "nearest view of the winning class.")
        .def_readonly("class_name", &Classification::class_name)
        .def_readonly("confidence", &Classification::confidence, "share of the k votes")
        .def_readonly("model", &Classification::best_model)
        .def_readonly("view", &Classification::best_view)
        .def_readonly("distance", &Classification::best_distance)
        .def_property_readonly(
            "pose", [](const Classification& c) { return matrix_array(c.pose); },
            "(4, 4) float32 model -> camera pose: of the nearest view of the class, or with "
            "verification the model aligned to the points (scale included)")
        .def_property_readonly(
            "fit",
            [](const Classification& c) -> std::optional<py::dict> {
                if (!c.fit) return std::nullopt;
                py::dict d;
                d["inliers"] = c.fit->inliers;
                d["support"] = c.fit->support;
                d["violations"] = c.fit->violations;
                d["rms_mm"] = c.fit->rms_mm;
                return d;
            },
            "with verification: {'inliers', 'support', 'violations', 'rms_mm'}; else None")
        .def_readonly("verified", &Classification::verified,
                      "with verification: the fit met the thresholds")
        .def_readonly("neighbours", &Classification::neighbours, "nearest first")
        .def("__repr__", &classification_repr);

    py::class_<RecognizedObject>(m, "SceneObject", "An object of a scene and its class.")
        .def_property_readonly("class_name",
                               [](const RecognizedObject& o) -> std::optional<std::string> {
                                   if (!o.classified()) return std::nullopt;
                                   return o.classification.class_name;
                               })
        .def_property_readonly("confidence",
                               [](const RecognizedObject& o) {
                                   return o.classified() ? o.classification.confidence : 0.0;
                               })
        .def_property_readonly("classification",
                               [](const RecognizedObject& o) -> std::optional<Classification> {
                                   if (!o.classified()) return std::nullopt;
                                   return o.classification;
                               })
        .def_property_readonly("pose",
                               [](const RecognizedObject& o) -> py::object {
                                   if (!o.classified()) return py::none();
                                   return matrix_array(o.classification.pose);
                               })
        .def_property_readonly(
            "points", [](const RecognizedObject& o) { return points_array(o.cluster.points); })
        .def_property_readonly(
            "centroid", [](const RecognizedObject& o) { return vector_array(o.cluster.centroid); })
        .def_property_readonly(
            "size", [](const RecognizedObject& o) { return vector_array(o.cluster.size); })
        .def_property_readonly(
            "truncated",
            [](const RecognizedObject& o) { return o.cluster.status != ClusterStatus::kOk; })
        .def_readonly("error", &RecognizedObject::error, "why it has no class; empty when it has")
        .def("__repr__", [](const RecognizedObject& o) {
            return "SceneObject(class_name=" +
                   (o.classified() ? "'" + o.classification.class_name + "'" : "None") +
                   ", points=" + std::to_string(o.cluster.points.size()) + ")";
        });

    py::class_<Recognizer>(m, "Recognizer",
                           "A trained database, opened read-only, with its k-NN index. Immutable "
                           "and thread-safe: its methods release the GIL.")
        .def(py::init([](const fs::path& database, std::size_t k, const std::string& descriptor,
                         bool use_weights, int samplings, const std::string& vote, bool every_view,
                         int threads, const std::optional<fs::path>& verify) {
                 RecognizerOptions options;
                 if (verify) options.verification_meshes = verify->string();
                 options.k = k;
                 options.descriptor = descriptor;
                 options.use_weights = use_weights;
                 options.query_samplings = samplings;
                 options.vote = parse_vote_rule(vote);
                 options.one_view_per_model = !every_view;
                 options.threads = threads;
                 py::gil_scoped_release release;
                 return with_files({&database}, [&] {
                     return std::make_unique<Recognizer>(database.string(), options);
                 });
             }),
             py::arg("database"), py::kw_only(), py::arg("k") = 10, py::arg("descriptor") = "",
             py::arg("use_weights") = true, py::arg("samplings") = 1, py::arg("vote") = "nearest",
             py::arg("every_view") = false, py::arg("threads") = 0, py::arg("verify") = py::none(),
             "Opens DATABASE (esf train ... -o DATABASE): the ``k`` nearest models (each by its "
             "nearest view; ``every_view``: the k nearest views) are the neighbours; ``vote`` "
             "'nearest' names the nearest one's class (the others give the confidence), "
             "'majority' the most frequent; ``descriptor`` picks the kind when it holds several; "
             "``use_weights`` applies its learned weights; ``samplings`` describes a query that "
             "many times and averages; ``threads`` 0 = all cores; ``verify``: the folder of meshes "
             "DATABASE was trained from, to align the nearest models to each object (then "
             "``Classification.pose`` is the fitted pose and ``.fit`` its score). Raises "
             "FileNotFoundError / "
             "OSError for a missing or broken file, "
             "ValueError for a database it cannot use.")
        .def("classify", &classify_py, py::arg("points"), py::arg("k") = py::none(),
             "Classifies one object's cloud ((N, 3) or (H, W, 3)) by the vote of its k nearest "
             "views (default: the Recognizer's k). Raises ValueError for a cloud without "
             "descriptor.")
        .def(
            "describe",
            [](const Recognizer& r, const py::object& points) {
                const PointsArg arg = points_arg(points);
                QueryDescriptor d;
                {
                    py::gil_scoped_release release;
                    d = r.describe(arg.points);
                }
                if (!d.ok()) throw std::invalid_argument(d.error);
                const auto dim = static_cast<py::ssize_t>(r.classifier().index().dimension());
                const auto rows = static_cast<py::ssize_t>(d.signatures.size()) / dim;
                return py::array_t<float>({rows, dim}, d.signatures.data());
            },
            py::arg("points"),
            "The query descriptor as the database's descriptor and settings make it: (S, D), "
            "one row per signature.")
        .def(
            "scene",
            [](const Recognizer& r, const py::object& points, const std::string& grouping,
               float plane_distance, float min_height, float max_height, float cluster_tolerance,
               std::size_t min_cluster_points, std::optional<std::vector<float>> viewpoint,
               std::uint64_t seed, int threads) {
                return scene_py(
                    r, points,
                    {grouping, plane_distance, min_height, max_height, cluster_tolerance,
                     min_cluster_points, std::move(viewpoint), seed, threads});
            },
            py::arg("points"), py::kw_only(), ESF_SEGMENT_ARGS,
            "Segments a table scene (as esf.segment) and classifies every object: a list of "
            "SceneObject, largest first (``class_name`` None where an object has no "
            "descriptor).")
        .def_property_readonly("k", [](const Recognizer& r) { return r.options().k; })
        .def_property_readonly("categories",
                               [](const Recognizer& r) { return r.info().categories; })
        .def_property_readonly("descriptor",
                               [](const Recognizer& r) { return r.info().setup.kind.name; })
        .def_property_readonly("views", [](const Recognizer& r) { return r.info().views; });

    m.def("evaluate", &evaluate_py, py::arg("database"), py::arg("test_set"), py::arg("k") = 10,
          py::kw_only(), py::arg("descriptor") = "", py::arg("use_weights") = true,
          py::arg("samplings") = 1, py::arg("threads") = 0,
          "Evaluates a labelled test set (a CSV with columns file and class) against a "
          "database: a dict with what ``esf eval DB TESTSET --json`` prints (1-NN and k-NN "
          "accuracy per sample and per class, confusion matrix, rank curves, timings).");

    py::class_<TrainingProgress>(m, "TrainingProgress", "What esf.train has done so far.")
        .def_readonly("models_total", &TrainingProgress::models_total)
        .def_readonly("models_done", &TrainingProgress::models_done)
        .def_readonly("models_existing", &TrainingProgress::models_existing)
        .def_readonly("models_failed", &TrainingProgress::models_failed)
        .def_readonly("views", &TrainingProgress::views)
        .def_readonly("views_skipped", &TrainingProgress::views_skipped)
        .def_readonly("model", &TrainingProgress::model, "'category/name' just finished")
        .def("__repr__", [](const TrainingProgress& p) {
            return "TrainingProgress(models_done=" + std::to_string(p.models_done) + "/" +
                   std::to_string(p.models_total) + ", views=" + std::to_string(p.views) + ")";
        });

    m.def("train", &train_py, py::arg("root"), py::arg("database"), py::kw_only(),
          py::arg("descriptor") = kTrainingDescriptor, py::arg("level") = 1,
          py::arg("samples") = 20000, py::arg("seed") = 0, py::arg("noise") = "kinect",
          py::arg("distance") = kTrainingCameraDistance,
          py::arg("max_distance") = kTrainingMaxCameraDistance,
          py::arg("min_elevation") = kTrainingMinElevation, py::arg("max_elevation") = 90.0,
          py::arg("min_points") = 50, py::arg("catalog") = py::none(),
          py::arg("use_catalog") = true, py::arg("threads") = 0, py::arg("progress") = py::none(),
          "Trains (or resumes) a database from ROOT/<category>/<model>.<ext> meshes, as "
          "``esf train``. ``progress`` is called with a TrainingProgress before the first and "
          "after every model. Ctrl-C, or an exception raised by ``progress``, stops training "
          "after the models committed so far; running again resumes. Returns the counts "
          "``esf train --json`` prints (without timings).");

    py::class_<RenderedView>(m, "View", "One rendered view of a mesh.")
        .def_readonly("index", &RenderedView::index, "view sphere index")
        .def_property_readonly(
            "points", [](const RenderedView& v) { return points_array(v.points); },
            "(N, 3) float32 points in the camera frame, metres")
        .def_property_readonly(
            "pose", [](const RenderedView& v) { return matrix_array(v.pose); },
            "(4, 4) float32 model -> camera")
        .def("__repr__", [](const RenderedView& v) {
            return "View(index=" + std::to_string(v.index) +
                   ", points=" + std::to_string(v.points.size()) + ")";
        });

    m.def("render", &render_py, py::arg("mesh"), py::kw_only(), py::arg("level") = 1,
          py::arg("width") = 640, py::arg("height") = 480, py::arg("fx") = py::none(),
          py::arg("fy") = py::none(), py::arg("cx") = py::none(), py::arg("cy") = py::none(),
          py::arg("fill") = 0.5, py::arg("distance") = py::none(),
          py::arg("max_distance") = py::none(), py::arg("min_elevation") = -90.0,
          py::arg("max_elevation") = 90.0, py::arg("noise") = "kinect", py::arg("seed") = 0,
          py::arg("scale") = 1.0, py::arg("extent") = py::none(), py::arg("threads") = 0,
          "Renders a mesh from the view sphere (level 1: 80 cameras) as a depth sensor sees it, "
          "as ``esf render``: a list of View (points in the camera frame, model -> camera "
          "pose). Defaults: Kinect v1 intrinsics, Kinect noise, camera distance from ``fill``.");

    py::class_<Database>(m, "Database", "A training database, opened read-only.")
        .def(py::init([](const fs::path& path) {
                 return with_files({&path},
                                   [&] { return std::make_unique<Database>(path.string()); });
             }),
             py::arg("path"))
        .def_property_readonly("path", &Database::path)
        .def_property_readonly(
            "settings",
            [](const Database& db) {
                py::dict out;
                for (const auto& [key, value] : db.settings())
                    out[py::str(key)] = setting_object(value);
                return out;
            },
            "every setting the database was trained with")
        .def_property_readonly(
            "categories",
            [](const Database& db) {
                py::list out;
                for (const CategoryInfo& c : db.summary().categories)
                    out.append(py::dict(py::arg("name") = c.name, py::arg("models") = c.models,
                                        py::arg("failed_models") = c.failed_models,
                                        py::arg("views") = c.views,
                                        py::arg("skipped_views") = c.skipped_views));
                return out;
            },
            "per category: name, models, failed_models, views, skipped_views")
        .def_property_readonly(
            "models",
            [](const Database& db) {
                py::list out;
                for (const ModelInfo& mi : db.models()) out.append(model_dict(mi));
                return out;
            },
            "per model: category, name, file, group, scale, status, error, views, skipped_views")
        .def_property_readonly("view_count", [](const Database& db) { return db.summary().views; })
        .def_property_readonly(
            "descriptor_kinds",
            [](const Database& db) {
                py::list out;
                for (const DescriptorKind& k : db.descriptor_kinds())
                    out.append(py::make_tuple(k.name, k.version, k.dimension));
                return out;
            },
            "(name, version, dimension) of each stored descriptor")
        .def(
            "views",
            [](const Database& db, const std::string& category, const std::string& model,
               const std::string& descriptor) {
                const int dim = kind_dimension(db, descriptor);
                py::list out;
                for (const ViewEntry& v : db.views(category, model, descriptor))
                    out.append(view_dict(v, dim));
                return out;
            },
            py::arg("category"), py::arg("model"), py::arg("descriptor") = "",
            "The views of one model: index, points, pose (4, 4), descriptors (S, D) or None, "
            "skip_reason.")
        .def(
            "descriptors",
            [](const Database& db, const std::string& descriptor) {
                DescriptorMatrix matrix = db.load_descriptors(descriptor);
                const auto dim = static_cast<py::ssize_t>(matrix.kind.dimension);
                py::array_t<float> data({static_cast<py::ssize_t>(matrix.rows()), dim},
                                        matrix.data.data());
                py::list classes, models;
                for (const DescriptorRow& r : matrix.row_info) {
                    classes.append(matrix.categories[r.category]);
                    models.append(matrix.models[r.model].name);
                }
                return py::make_tuple(data, classes, models);
            },
            py::arg("descriptor") = "",
            "All descriptors of a kind as (X, classes, models): X (rows, D) float32, and the "
            "class and model name of each row (ready for scikit-learn).");
}
