// The `esf` Python module (esf._esf): the C++ core with numpy arrays in and out. Thin: every
// function converts its arguments (python/src/points.hpp), releases the GIL, calls the library
// and converts the result back. Errors: std::invalid_argument -> ValueError, esf::IoError ->
// OSError (FileNotFoundError when the named file does not exist), with the library's messages.
// Keyword defaults are those of default-constructed option structs of the library.
//
// One file per part: clouds.cpp, descriptors.cpp, segmentation.cpp, recognition.cpp,
// training.cpp, database.cpp (bindings.hpp declares them).

#include <pybind11/pybind11.h>

#include <exception>

#include "bindings.hpp"
#include "esf/core/error.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"

namespace esf::python {

namespace {

void translate_exception(std::exception_ptr p) {
    try {
        if (p) std::rethrow_exception(p);
    } catch (const FileNotFound& e) {
        PyErr_SetString(PyExc_FileNotFoundError, e.what());
    } catch (const IoError& e) {
        PyErr_SetString(PyExc_OSError, e.what());
    }
}

}  // namespace

}  // namespace esf::python

PYBIND11_MODULE(_esf, m) {
    m.doc() =
        "ESF (Ensemble of Shape Functions) descriptors, training on CAD models and table-scene "
        "recognition: the esf C++ library with numpy arrays in and out.";
    m.attr("__version__") = ESF_VERSION;
    m.attr("ESF_SIZE") = esf::kEsfSize;
    pybind11::register_exception_translator(&esf::python::translate_exception);

    esf::python::bind_clouds(m);
    esf::python::bind_descriptors(m);
    esf::python::bind_segmentation(m);
    esf::python::bind_recognition(m);
    esf::python::bind_training(m);
    esf::python::bind_database(m);
}
