#pragma once
// The keyword arguments of esf.segment and Recognizer.scene: a few of SegmentationOptions, with
// its defaults (the others keep theirs).

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "esf/core/enum_names.hpp"
#include "esf/segmentation/segmentation.hpp"
#include "points.hpp"

namespace esf::python {

struct SegmentArgs {
    std::string grouping;
    float plane_distance;
    float min_height;
    float max_height;
    float cluster_tolerance;
    std::size_t min_cluster_points;
    std::optional<std::vector<float>> viewpoint;  ///< none: SegmentationOptions' viewpoint
    std::uint64_t seed;
    int threads;

    /// SegmentationOptions with these values; throws std::invalid_argument for a bad one.
    SegmentationOptions options() const;
};

/// Defines `name` on `target` (the module, or a class whose `f` takes the object first) with
/// the arguments (points, *, grouping, plane_distance, min_height, max_height,
/// cluster_tolerance, min_cluster_points, viewpoint, seed, threads), defaulting to those of a
/// default SegmentationOptions.
template <typename Target, typename F>
void def_with_segment_args(Target& target, const char* name, F&& f, const char* doc) {
    const SegmentationOptions defaults;
    target.def(name, std::forward<F>(f), py::arg("points"), py::kw_only(),
               py::arg("grouping") = to_string(defaults.grouping),
               py::arg("plane_distance") = defaults.plane_distance,
               py::arg("min_height") = defaults.min_height,
               py::arg("max_height") = defaults.max_height,
               py::arg("cluster_tolerance") = defaults.cluster_tolerance,
               py::arg("min_cluster_points") = defaults.min_cluster_points,
               py::arg("viewpoint") = py::none(), py::arg("seed") = defaults.seed,
               py::arg("threads") = defaults.threads, doc);
}

}  // namespace esf::python
