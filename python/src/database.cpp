// Training databases from the `esf` Python module: Database (read-only).

#include "esf/training/database.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdint>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "bindings.hpp"
#include "esf/core/enum_names.hpp"

namespace esf::python {

namespace {

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

}  // namespace

void bind_database(py::module_& m) {
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

}  // namespace esf::python
