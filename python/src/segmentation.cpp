// Table-scene segmentation from the `esf` Python module: segment, Cluster, Segmentation.

#include "esf/segmentation/segmentation.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "esf/core/enum_names.hpp"
#include "segment_args.hpp"

namespace esf::python {

SegmentationOptions SegmentArgs::options() const {
    SegmentationOptions o;
    o.grouping = parse_enum<Grouping>(grouping);
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

namespace {

SegmentationResult segment_py(const py::object& points, const SegmentArgs& args) {
    const PointsArg arg = points_arg(points);
    const SegmentationOptions options = args.options();
    py::gil_scoped_release release;
    return segment_scene(arg.cloud(), options);
}

}  // namespace

void bind_segmentation(py::module_& m) {
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

    def_with_segment_args(
        m, "segment",
        [](const py::object& points, const std::string& grouping, float plane_distance,
           float min_height, float max_height, float cluster_tolerance,
           std::size_t min_cluster_points, std::optional<std::vector<float>> viewpoint,
           std::uint64_t seed, int threads) {
            return segment_py(points,
                              {grouping, plane_distance, min_height, max_height, cluster_tolerance,
                               min_cluster_points, std::move(viewpoint), seed, threads});
        },
        "Segments a table scene ((H, W, 3) organised or (N, 3)): the dominant plane, and the "
        "objects above it as clusters (largest first). ``grouping`` is 'convexity' (surface "
        "patches joined where the surface is convex: objects part at concave creases) or "
        "'euclidean' (all that touches is one object); lengths in metres. A scene without plane "
        "or objects is no error: see ``message``.");
}

}  // namespace esf::python
