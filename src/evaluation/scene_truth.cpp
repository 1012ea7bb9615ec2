#include "esf/evaluation/scene_truth.hpp"

#include <exception>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "esf/core/error.hpp"

namespace fs = std::filesystem;

namespace esf {

std::optional<SceneTruth> read_scene_truth(const std::string& scene_set) {
    const fs::path path = fs::path(scene_set).parent_path() / "truth.json";
    if (!fs::is_regular_file(path)) return std::nullopt;
    std::ifstream in(path);
    nlohmann::json j;
    try {
        in >> j;
        SceneTruth truth;
        truth.root = j.at("root").get<std::string>();
        for (const auto& scene : j.at("scenes"))
            for (const auto& o : scene.at("objects")) {
                TruthObject t;
                t.model = o.at("model").get<std::string>();
                t.class_name = o.at("class").get<std::string>();
                t.visible = o.at("visible").get<double>();
                const auto& m = o.at("pose");
                if (m.size() != 16)
                    throw std::invalid_argument("a pose of " + std::to_string(m.size()) +
                                                " numbers");
                for (int k = 0; k < 16; ++k)
                    t.pose(k / 4, k % 4) = m.at(static_cast<std::size_t>(k)).get<double>();
                truth.objects[{scene.at("file").get<std::string>(),
                               o.at("object_id").get<std::uint32_t>()}] = t;
            }
        return truth;
    } catch (const std::exception& e) {
        throw IoError(
            file_message(path.string(), 0, std::string("not a scene truth file: ") + e.what()));
    }
}

}  // namespace esf
