// The truth of a generated scene set (truth.json, written by `esf generate-scenes` beside its
// scenes.csv): each object's class, model, pose and visible share, by scene file and object id.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>

namespace esf {

struct TruthObject {
    std::string model;  ///< mesh file, relative to SceneTruth::root
    std::string class_name;
    Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();  ///< mesh file coordinates -> camera
    double visible = 0.0;                                ///< share of the object in view, 0-1
};

struct SceneTruth {
    std::string root;  ///< the mesh folder the scenes were generated from
    /// By (scene file name as truth.json gives it, object id).
    std::map<std::pair<std::string, std::uint32_t>, TruthObject> objects;
};

/// Reads truth.json beside the scene set CSV `scene_set` (its folder); std::nullopt when there is
/// none. Throws esf::IoError naming the file for one that is not a scene truth file (bad JSON, a
/// number beyond double's range, a missing field, a pose that is not 16 numbers, an object id
/// outside [0, 2^32 - 1], a visible share outside [0, 1]).
std::optional<SceneTruth> read_scene_truth(const std::string& scene_set);

}  // namespace esf
