#include "points.hpp"

#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

namespace esf::python {

static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "Vector3f must be three packed floats");

namespace {

std::string shape_text(const py::array& array) {
    std::string out = "(";
    for (py::ssize_t i = 0; i < array.ndim(); ++i)
        out += (i ? ", " : "") + std::to_string(array.shape(i));
    return out + (array.ndim() == 1 ? ",)" : ")");
}

std::string type_name(py::handle object) {
    return py::str(py::type::handle_of(object).attr("__name__")).cast<std::string>();
}

}  // namespace

PointCloud PointsArg::cloud() const {
    PointCloud out;
    out.points.assign(points.begin(), points.end());
    out.width = width;
    out.height = height;
    return out;
}

PointsArg points_arg(py::handle object, const std::string& name) {
    const std::string expected = name + ": expected an (N, 3) or (H, W, 3) array of numbers";
    if (object.is_none() || py::isinstance<py::str>(object) || py::isinstance<py::bytes>(object))
        throw py::type_error(expected + ", got " + type_name(object));
    py::object source = py::reinterpret_borrow<py::object>(object);
    // Open3D's PointCloud (and anything shaped like it) carries its points as an attribute.
    if (!py::isinstance<py::array>(source) && py::hasattr(source, "points"))
        source = source.attr("points");
    py::array array;
    if (py::isinstance<py::array>(source)) {
        array = py::reinterpret_borrow<py::array>(source);
    } else {
        try {
            array = py::module_::import("numpy").attr("asarray")(source);
        } catch (const py::error_already_set&) {
            throw py::type_error(expected + ", got " + type_name(object));
        }
    }
    const char kind = array.dtype().kind();
    if (array.ndim() == 0) throw py::type_error(expected + ", got " + type_name(object));
    if (kind != 'f' && kind != 'i' && kind != 'u')
        throw py::type_error(expected + ", got dtype " +
                             py::str(array.dtype()).cast<std::string>());
    const bool organised = array.ndim() == 3;
    if ((array.ndim() != 2 && !organised) || array.shape(array.ndim() - 1) != 3)
        throw py::value_error(name + ": expected shape (N, 3) or (H, W, 3), got " +
                              shape_text(array));
    PointsArg out;
    // Returns `array` itself when it is already C-contiguous, aligned float32: no copy.
    out.array = FloatArray::ensure(array);
    if (!out.array) throw py::error_already_set();
    const auto count = static_cast<std::size_t>(out.array.size() / 3);
    out.points = {reinterpret_cast<const Eigen::Vector3f*>(out.array.data()), count};
    out.height = organised ? static_cast<std::uint32_t>(array.shape(0)) : 1;
    out.width = static_cast<std::uint32_t>(organised ? array.shape(1) : array.shape(0));
    return out;
}

namespace {

/// A float32 array over the coordinates of `points`, which it owns (moved, no copy).
py::array_t<float> owning_array(Points points, std::vector<py::ssize_t> shape) {
    auto owned = std::make_unique<Points>(std::move(points));
    const float* data = owned->empty() ? nullptr : owned->front().data();
    py::capsule owner(owned.get(), [](void* p) { delete static_cast<Points*>(p); });
    owned.release();
    return py::array_t<float>(std::move(shape), data, owner);
}

}  // namespace

py::array_t<float> organised_array(Points points, std::size_t height, std::size_t width) {
    if (points.size() != height * width)
        throw std::invalid_argument("organised_array: " + std::to_string(points.size()) +
                                    " points are not " + std::to_string(height) + " x " +
                                    std::to_string(width));
    return owning_array(std::move(points),
                        {static_cast<py::ssize_t>(height), static_cast<py::ssize_t>(width), 3});
}

py::array_t<float> points_array(Points points) {
    const auto n = static_cast<py::ssize_t>(points.size());
    return owning_array(std::move(points), {n, 3});
}

py::array_t<float> matrix_array(const Eigen::Matrix4f& matrix) {
    py::array_t<float> out({4, 4});
    auto m = out.mutable_unchecked<2>();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = matrix(r, c);
    return out;
}

py::array_t<float> vector_array(const Eigen::Vector3f& vector) {
    py::array_t<float> out(3);
    auto v = out.mutable_unchecked<1>();
    for (int i = 0; i < 3; ++i) v(i) = vector[i];
    return out;
}

}  // namespace esf::python
