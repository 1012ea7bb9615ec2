// Recognition from the `esf` Python module: Recognizer (classify, describe, scene), its
// results (Neighbour, Classification, SceneObject) and evaluate.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "esf/core/enum_names.hpp"
#include "esf/evaluation/evaluation.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/report/report.hpp"
#include "segment_args.hpp"

namespace esf::python {

namespace {

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

std::string classification_repr(const Classification& c) {
    return "Classification(class_name='" + c.class_name +
           "', confidence=" + std::to_string(c.confidence) + ", model='" + c.best_model +
           "', view=" + std::to_string(c.best_view) +
           ", distance=" + std::to_string(c.best_distance) + ")";
}

}  // namespace

void bind_recognition(py::module_& m) {
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

    const RecognizerOptions defaults;
    py::class_<Recognizer> recognizer(m, "Recognizer",
                                      "A trained database, opened read-only, with its k-NN "
                                      "index. Immutable and thread-safe: its methods release "
                                      "the GIL.");
    recognizer
        .def(py::init([](const fs::path& database, std::size_t k, const std::string& descriptor,
                         bool use_weights, int samplings, const std::string& vote, bool every_view,
                         int threads, bool verify, const std::optional<fs::path>& verify_meshes,
                         std::size_t candidates, bool verify_within_class, bool merge_parts,
                         double shape_weight, bool fixed_sizes, bool two_way_icp) {
                 RecognizerOptions options;
                 options.verification.two_way = two_way_icp;
                 options.merge_parts = merge_parts;
                 options.verification.shape_weight = shape_weight;
                 options.verification.every_size_free = !fixed_sizes;
                 options.verify = verify;
                 if (verify_meshes) options.verification_meshes = verify_meshes->string();
                 options.verification.candidates = candidates;
                 options.verification.decide_class = !verify_within_class;
                 options.k = k;
                 options.descriptor = descriptor;
                 options.use_weights = use_weights;
                 options.query_samplings = samplings;
                 options.vote = parse_enum<VoteRule>(vote);
                 options.one_view_per_model = !every_view;
                 options.threads = threads;
                 py::gil_scoped_release release;
                 return with_files({&database}, [&] {
                     return std::make_unique<Recognizer>(database.string(), options);
                 });
             }),
             py::arg("database"), py::kw_only(), py::arg("k") = defaults.k,
             py::arg("descriptor") = defaults.descriptor,
             py::arg("use_weights") = defaults.use_weights,
             py::arg("samplings") = defaults.query_samplings,
             py::arg("vote") = to_string(defaults.vote),
             py::arg("every_view") = !defaults.one_view_per_model,
             py::arg("threads") = defaults.threads, py::arg("verify") = defaults.verify,
             py::arg("verify_meshes") = py::none(),
             py::arg("candidates") = defaults.verification.candidates,
             py::arg("verify_within_class") = !defaults.verification.decide_class,
             py::arg("merge_parts") = defaults.merge_parts,
             py::arg("shape_weight") = defaults.verification.shape_weight,
             py::arg("fixed_sizes") = !defaults.verification.every_size_free,
             py::arg("two_way_icp") = defaults.verification.two_way,
             "Opens DATABASE (esf train ... -o DATABASE): the ``k`` nearest models (each by its "
             "nearest view; ``every_view``: the k nearest views) are the neighbours; ``vote`` "
             "'nearest' names the nearest one's class (the others give the confidence), "
             "'majority' the most frequent; ``descriptor`` picks the kind when it holds several; "
             "``use_weights`` applies its learned weights; ``samplings`` describes a query that "
             "many times and averages; ``threads`` 0 = all cores; ``verify`` aligns the "
             "``candidates`` "
             "nearest models to each object with the surfaces the database stores (or those of "
             "the meshes in ``verify_meshes``, the folder DATABASE was trained from), and the "
             "best fit names class (only the neighbours' class with ``verify_within_class``), "
             "model and pose: ``Classification.pose`` is the fitted pose and ``.fit`` its "
             "score; ``verification`` says whether it is on. In scenes with a frame, "
             "``merge_parts`` makes two neighbouring objects one when one model fitted to both "
             "explains them better than their own fits. ``shape_weight`` (0 to 2): candidates "
             "compete by fit score less this times the gap between the object's and the "
             "model's cylinder-box contrast. ``fixed_sizes`` fits the size of only the models "
             "whose size the catalog guesses (default: every model's size within [0.8, 1.25] "
             "while the candidates compete). ``two_way_icp`` pairs the object's points with "
             "the model too, for better poses and sizes where the database holds the objects' "
             "own models (verification takes about 1.5 times as long). Raises "
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
            "one row per signature.");
    def_with_segment_args(
        recognizer, "scene",
        [](const Recognizer& r, const py::object& points, const std::string& grouping,
           float plane_distance, float min_height, float max_height, float cluster_tolerance,
           std::size_t min_cluster_points, std::optional<std::vector<float>> viewpoint,
           std::uint64_t seed, int threads) {
            return scene_py(r, points,
                            {grouping, plane_distance, min_height, max_height, cluster_tolerance,
                             min_cluster_points, std::move(viewpoint), seed, threads});
        },
        "Segments a table scene (as esf.segment) and classifies every object: a list of "
        "SceneObject, largest first (``class_name`` None where an object has no descriptor).");
    recognizer.def_property_readonly("k", [](const Recognizer& r) { return r.options().k; })
        .def_property_readonly("categories",
                               [](const Recognizer& r) { return r.info().categories; })
        .def_property_readonly("descriptor",
                               [](const Recognizer& r) { return r.info().setup.kind.name; })
        .def_property_readonly("views", [](const Recognizer& r) { return r.info().views; })
        .def_property_readonly(
            "verification", [](const Recognizer& r) { return r.info().verification; },
            "How classifications are verified: 'stored surfaces', 'meshes of ROOT', 'off' or "
            "'off: ' and why.");

    m.def("evaluate", &evaluate_py, py::arg("database"), py::arg("test_set"),
          py::arg("k") = EvaluationOptions{}.k, py::kw_only(),
          py::arg("descriptor") = defaults.descriptor,
          py::arg("use_weights") = defaults.use_weights,
          py::arg("samplings") = defaults.query_samplings,
          py::arg("threads") = EvaluationOptions{}.threads,
          "Evaluates a labelled test set (a CSV with columns file and class) against a "
          "database: a dict with what ``esf eval DB TESTSET --json`` prints (1-NN and k-NN "
          "accuracy per sample and per class, confusion matrix, rank curves, timings).");
}

}  // namespace esf::python
