// Point clouds in and out of the `esf` Python module: as_points, read_cloud, write_cloud.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl/filesystem.h>

#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>

#include "bindings.hpp"
#include "esf/core/enum_names.hpp"
#include "esf/core/point_cloud.hpp"
#include "esf/io/cloud_io.hpp"

namespace esf::python {

namespace {

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
    const PcdEncoding e = parse_enum<PcdEncoding>(encoding);
    const PointsArg arg = points_arg(points);
    py::gil_scoped_release release;
    const PointCloud cloud = arg.cloud();
    write_pcd(path.string(), cloud, e);
}

}  // namespace

void bind_clouds(py::module_& m) {
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
          py::arg("encoding") = to_string(PcdEncoding::kBinary),  // write_pcd()'s default
          "Writes points ((N, 3), or (H, W, 3) kept organised) to a PCD file; ``encoding`` is "
          "'binary', 'ascii' or 'binary_compressed'. The file appears complete or not at all.");
}

}  // namespace esf::python
