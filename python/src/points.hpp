#pragma once
// Point arrays between numpy and esf: any (N, 3) or (H, W, 3) array-like of numbers in, a span
// of Eigen::Vector3f over float32 memory out. A C-contiguous, aligned float32 array is used in
// place; anything else is converted once. Python errors: TypeError for what is not an array of
// numbers, ValueError for a wrong shape.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <span>
#include <string>

#include "esf/core/point_cloud.hpp"

namespace esf::python {

namespace py = pybind11;

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

/// Points borrowed from a Python object; `array` keeps the memory alive.
struct PointsArg {
    FloatArray array;
    std::span<const Eigen::Vector3f> points;
    std::uint32_t width = 0;   ///< (H, W, 3): W; (N, 3): N
    std::uint32_t height = 1;  ///< (H, W, 3): H; (N, 3): 1

    /// A PointCloud copy with the organised layout (segmentation wants one).
    PointCloud cloud() const;
};

/// Converts `object` (an ndarray, anything numpy.asarray takes, or an object with a `points`
/// attribute such as an Open3D PointCloud). `name` names the argument in messages. Must be
/// called with the GIL held.
PointsArg points_arg(py::handle object, const std::string& name = "points");

/// An (N, 3) float32 array that owns `points` (moved, no copy).
py::array_t<float> points_array(Points points);
/// An (H, W, 3) float32 array that owns `points` (H * W of them).
py::array_t<float> organised_array(Points points, std::size_t height, std::size_t width);
/// A copy of a 4x4 matrix as a (4, 4) float32 array.
py::array_t<float> matrix_array(const Eigen::Matrix4f& matrix);
/// A copy of a 3-vector as a (3,) float32 array.
py::array_t<float> vector_array(const Eigen::Vector3f& vector);

}  // namespace esf::python
