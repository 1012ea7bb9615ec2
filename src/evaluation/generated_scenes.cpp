// Writing a folder of generated scenes and their truth (esf/evaluation/generated_scenes.hpp).

#include "esf/evaluation/generated_scenes.hpp"

#include <cstdio>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/atomic_file.hpp"
#include "esf/core/parallel.hpp"
#include "esf/io/cloud_io.hpp"
#include "evaluation/matrix_json.hpp"
#include "evaluation/scene_generation.hpp"

namespace esf {

namespace fs = std::filesystem;

namespace {

std::string scene_file_name(std::size_t index) {
    char name[32];
    std::snprintf(name, sizeof name, "scene_%04zu.pcd", index);
    return name;
}

// A CSV field, quoted when it holds a comma, a quote or a line break (RFC 4180).
std::string csv_field(const std::string& text) {
    if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
    std::string out = "\"";
    for (const char c : text) {
        if (c == '"') out += '"';
        out += c;
    }
    return out + '"';
}

void write_text(const fs::path& path, const std::string& text) {
    detail::write_file_atomically(path, text.data(), text.size());
}

}  // namespace

GeneratedSceneSet generate_scenes(const std::string& root, const std::string& output,
                                  const SceneGenerationOptions& options) {
    if (options.scenes == 0) throw std::invalid_argument("generate_scenes: no scenes asked for");
    if (options.scenes > 100000)
        throw std::invalid_argument("generate_scenes: at most 100000 scenes, got " +
                                    std::to_string(options.scenes));
    const int threads = resolve_threads(options.threads);
    const ClutterComposer composer(
        detail::load_clutter_models(root, options.catalog, options.use_catalog, options.groups,
                                    threads),
        options.clutter);
    detail::create_output_folder(output);

    GeneratedSceneSet result;
    result.models = composer.models().size();
    result.per_type.assign(clutter_types().size(), 0);
    std::vector<std::vector<ClutterObject>> objects(options.scenes);
    std::vector<nlohmann::json> truths(options.scenes);
    std::mutex progress_mutex;
    std::size_t done = 0;
    parallel_for(options.scenes, threads, [&](std::size_t index) {
        ClutterScene scene = composer.compose(index);
        const std::string name = scene_file_name(index);
        write_pcd((fs::path(output) / name).string(), scene.cloud, PcdEncoding::kBinaryCompressed);
        nlohmann::json truth = {{"file", name},
                                {"type", to_string(scene.type)},
                                {"wall", scene.wall},
                                {"table_edge", scene.table_edge},
                                {"camera", detail::row_major_json(scene.world_to_camera.matrix())}};
        truth["objects"] = nlohmann::json::array();
        for (const ClutterObject& o : scene.objects) {
            const ClutterModel& m = composer.models()[o.model];
            truth["objects"].push_back({{"object_id", o.object_id},
                                        {"class", m.category},
                                        {"model", m.file},
                                        {"pose", detail::row_major_json(o.pose)},
                                        {"scale", m.scale},
                                        {"size", o.size},
                                        {"visible", o.visible},
                                        {"pixels", o.pixels},
                                        {"labelled", o.labelled},
                                        {"placement", o.placement},
                                        {"type", to_string(scene.type)}});
        }
        truths[index] = std::move(truth);
        objects[index] = std::move(scene.objects);
        if (options.progress) {
            const std::lock_guard<std::mutex> lock(progress_mutex);
            options.progress(++done, options.scenes);
        }
    });

    std::string csv = "scene_file,object_id,class,scene_type\n";
    nlohmann::json truth = {{"seed", options.clutter.seed},
                            {"root", fs::absolute(root).lexically_normal().string()}};
    truth["scenes"] = nlohmann::json::array();
    for (std::size_t index = 0; index < options.scenes; ++index) {
        const ClutterType type = composer.type_of(index);
        ++result.per_type[static_cast<std::size_t>(type)];
        result.files.push_back((fs::path(output) / scene_file_name(index)).string());
        for (const ClutterObject& o : objects[index]) {
            ++result.objects;
            if (!o.labelled) continue;
            ++result.labelled;
            csv += scene_file_name(index) + "," + std::to_string(o.object_id) + "," +
                   csv_field(composer.models()[o.model].category) + "," + to_string(type) + "\n";
        }
        truth["scenes"].push_back(std::move(truths[index]));
    }
    const fs::path csv_path = fs::path(output) / "scenes.csv";
    const fs::path truth_path = fs::path(output) / "truth.json";
    write_text(csv_path, csv);
    write_text(truth_path, truth.dump(1) + "\n");
    result.files.push_back(csv_path.string());
    result.files.push_back(truth_path.string());
    return result;
}

}  // namespace esf
