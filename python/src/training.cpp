// Training and rendering from the `esf` Python module: train (with TrainingProgress) and
// render (a list of View).

#include "esf/training/training.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "esf/core/enum_names.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/render/render.hpp"
#include "esf/render/sensor_model.hpp"
#include "esf/training/database.hpp"

namespace esf::python {

namespace {

py::dict train_py(const fs::path& root, const fs::path& database, const std::string& descriptor,
                  int level, int samples, std::uint64_t seed, const std::string& noise,
                  std::optional<double> distance, std::optional<double> max_distance,
                  double min_elevation, double max_elevation, std::size_t min_points,
                  std::size_t occlusions, std::optional<fs::path> catalog, bool use_catalog,
                  int threads, std::optional<py::function> progress) {
    TrainingOptions options;
    options.render.level = level;
    options.render.noise = parse_enum<SensorNoise>(noise);
    options.render.distance = distance;
    options.render.max_distance = max_distance;
    options.render.min_elevation = min_elevation;
    options.render.max_elevation = max_elevation;
    options.descriptor = descriptor;
    options.esf.samples = samples;
    options.descriptor_options.samples = samples;
    options.seed = seed;
    options.min_points = min_points;
    options.occlusions = occlusions;
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
    options.noise = parse_enum<SensorNoise>(noise);
    options.seed = seed;
    options.scale = scale;
    options.target_extent = extent;
    options.threads = threads;
    py::gil_scoped_release release;
    const Mesh mesh = with_files({&mesh_path}, [&] { return load_mesh(mesh_path.string()); });
    return render_views(mesh, options);
}

}  // namespace

void bind_training(py::module_& m) {
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

    const TrainingOptions training;
    m.def("train", &train_py, py::arg("root"), py::arg("database"), py::kw_only(),
          py::arg("descriptor") = training.descriptor, py::arg("level") = training.render.level,
          py::arg("samples") = training.descriptor_options.samples, py::arg("seed") = training.seed,
          py::arg("noise") = to_string(training.render.noise),
          py::arg("distance") = training.render.distance,
          py::arg("max_distance") = training.render.max_distance,
          py::arg("min_elevation") = training.render.min_elevation,
          py::arg("max_elevation") = training.render.max_elevation,
          py::arg("min_points") = training.min_points, py::arg("occlusions") = training.occlusions,
          py::arg("catalog") = py::none(), py::arg("use_catalog") = training.use_catalog,
          py::arg("threads") = training.threads, py::arg("progress") = py::none(),
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

    const RenderOptions rendering;
    m.def("render", &render_py, py::arg("mesh"), py::kw_only(), py::arg("level") = rendering.level,
          py::arg("width") = rendering.camera.width, py::arg("height") = rendering.camera.height,
          py::arg("fx") = py::none(), py::arg("fy") = py::none(), py::arg("cx") = py::none(),
          py::arg("cy") = py::none(), py::arg("fill") = rendering.fill_fraction,
          py::arg("distance") = rendering.distance,
          py::arg("max_distance") = rendering.max_distance,
          py::arg("min_elevation") = rendering.min_elevation,
          py::arg("max_elevation") = rendering.max_elevation,
          py::arg("noise") = to_string(rendering.noise), py::arg("seed") = rendering.seed,
          py::arg("scale") = rendering.scale, py::arg("extent") = rendering.target_extent,
          py::arg("threads") = rendering.threads,
          "Renders a mesh from the view sphere (level 1: 80 cameras) as a depth sensor sees it, "
          "as ``esf render``: a list of View (points in the camera frame, model -> camera "
          "pose). Defaults: Kinect v1 intrinsics, Kinect noise, camera distance from ``fill``.");
}

}  // namespace esf::python
