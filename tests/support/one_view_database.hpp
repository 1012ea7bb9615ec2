#pragma once
// Writes a small ESF database for tests: one model with one view per class, described with
// 2,000 triples and seed 4 (and those settings stored, so queries describe alike).

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/training/database.hpp"

namespace esf::test {

inline EsfOptions one_view_database_options() {
    EsfOptions options;
    options.samples = 2000;
    options.seed = 4;
    return options;
}

/// Model "<class>_1" of category <class>, its one view the ESF descriptor of `points`.
inline void write_one_view_database(const std::string& path,
                                    const std::vector<std::pair<std::string, Points>>& classes) {
    const EsfOptions options = one_view_database_options();
    Database db(path, OpenMode::kWrite);
    db.set_settings({{"esf_samples", std::int64_t{options.samples}},
                     {"seed", static_cast<std::int64_t>(options.seed)}});
    db.add_descriptor_kind({"esf", kEsfVersion, kEsfSize});
    for (const auto& [name, points] : classes) {
        ModelEntry model;
        model.category = name;
        model.name = name + "_1";
        model.file = name + "/" + name + "_1.ply";
        ViewEntry view;
        view.points = points.size();
        const EsfResult r = compute_esf(points, options);
        view.descriptors.assign(r.descriptor.begin(), r.descriptor.end());
        model.views.push_back(view);
        db.write_model(model, "esf");
    }
}

}  // namespace esf::test
