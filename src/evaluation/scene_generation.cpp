// The models and output folder of generated scenes and sequences (evaluation/scene_generation.hpp).

#include "evaluation/scene_generation.hpp"

#include <filesystem>
#include <system_error>
#include <utility>

#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "esf/mesh/mesh.hpp"

namespace esf::detail {

std::vector<ClutterModel> load_clutter_models(const std::string& root, const std::string& catalog,
                                              bool use_catalog, const GroupSelection& groups,
                                              int threads) {
    const std::vector<PlannedModel> plans = plan_models(root, catalog, use_catalog, groups);
    std::vector<ClutterModel> models(plans.size());
    parallel_for(plans.size(), threads, [&](std::size_t i) {
        ClutterModel& m = models[i];
        Mesh mesh = load_mesh(plans[i].file.path);
        m.scale = plans[i].scale(mesh);
        m.mesh = scaled_mesh(std::move(mesh), m.scale);
        m.category = plans[i].file.category;
        m.file = plans[i].file.file;
    });
    return models;
}

void create_output_folder(const std::string& folder) {
    std::error_code error;
    std::filesystem::create_directories(folder, error);
    if (error || !std::filesystem::is_directory(folder))
        throw IoError(file_message(folder, 0, "cannot create the output folder"));
}

}  // namespace esf::detail
