#include "esf/evaluation/scene_truth.hpp"

#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
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
                if (!(t.visible >= 0.0 && t.visible <= 1.0))
                    throw std::invalid_argument("a visible share of " + std::to_string(t.visible));
                const auto& m = o.at("pose");
                if (!m.is_array() || m.size() != 16)
                    throw std::invalid_argument("a pose of " + std::to_string(m.size()) +
                                                " numbers");
                for (int k = 0; k < 16; ++k)
                    t.pose(k / 4, k % 4) = m.at(static_cast<std::size_t>(k)).get<double>();
                const auto id = o.at("object_id").get<std::int64_t>();
                if (id < 0 || id > std::numeric_limits<std::uint32_t>::max())
                    throw std::invalid_argument("an object id of " + std::to_string(id));
                truth.objects[{scene.at("file").get<std::string>(),
                               static_cast<std::uint32_t>(id)}] = t;
            }
        return truth;
    } catch (const std::exception& e) {
        throw IoError(
            file_message(path.string(), 0, std::string("not a scene truth file: ") + e.what()));
    }
}

}  // namespace esf
