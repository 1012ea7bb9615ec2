#pragma once
// What the binding files of the `esf` Python module share: the exception for a missing file,
// the function that raises it, and one bind_<part>() per file, called by PYBIND11_MODULE
// (module.cpp) in this order.

#include <pybind11/pybind11.h>

#include <filesystem>
#include <initializer_list>
#include <stdexcept>
#include <system_error>

#include "esf/core/error.hpp"
#include "points.hpp"

namespace esf::python {

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

void bind_clouds(py::module_& m);        ///< as_points, read_cloud, write_cloud (clouds.cpp)
void bind_descriptors(py::module_& m);   ///< describe, describe_batch (descriptors.cpp)
void bind_segmentation(py::module_& m);  ///< Cluster, Segmentation, segment (segmentation.cpp)
/// Neighbour, Classification, SceneObject, Recognizer, evaluate (recognition.cpp).
void bind_recognition(py::module_& m);
void bind_training(py::module_& m);  ///< TrainingProgress, train, View, render (training.cpp)
void bind_database(py::module_& m);  ///< Database (database.cpp)

}  // namespace esf::python
