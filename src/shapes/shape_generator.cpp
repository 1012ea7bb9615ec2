#include "esf/shapes/shape_generator.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <system_error>

#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "shapes/shape_categories.hpp"

namespace esf {

namespace {

using Builder = shapes::Surface (*)(shapes::Rng&);

struct Category {
    const char* name;
    Builder build;
    bool paper = true;  // one of the paper's ten (generated unless categories are named)
};

constexpr Category kCategories[] = {
    {"apple", shapes::make_apple},
    {"banana", shapes::make_banana},
    {"bottle", shapes::make_bottle},
    {"bowl", shapes::make_bowl},
    {"can", shapes::make_can, false},
    {"car", shapes::make_car},
    {"donut", shapes::make_donut},
    {"hammer", shapes::make_hammer},
    {"mug", shapes::make_mug},
    {"tetra_pak", shapes::make_tetra_pak},
    {"toilet_paper", shapes::make_toilet_paper},
};

std::string known_list() {
    std::string list;
    for (const Category& c : kCategories) list += (list.empty() ? "" : ", ") + std::string(c.name);
    return list;
}

Builder find_builder(const std::string& category) {
    for (const Category& c : kCategories)
        if (category == c.name) return c.build;
    throw std::invalid_argument("unknown category '" + category + "' (known: " + known_list() +
                                ")");
}

struct Job {
    std::string category;
    int index;
};

std::vector<Job> plan(const GeneratorOptions& options) {
    if (options.per_class < 1)
        throw std::invalid_argument("per_class must be >= 1, got " +
                                    std::to_string(options.per_class));
    resolve_threads(options.threads);  // rejects negative counts
    const std::vector<std::string> categories =
        options.categories.empty() ? generated_categories() : options.categories;
    for (std::size_t i = 0; i < categories.size(); ++i) {
        find_builder(categories[i]);
        if (std::find(categories.begin(), categories.begin() + static_cast<std::ptrdiff_t>(i),
                      categories[i]) != categories.begin() + static_cast<std::ptrdiff_t>(i))
            throw std::invalid_argument("category '" + categories[i] + "' given twice");
    }
    std::vector<Job> jobs;
    for (const std::string& category : categories)
        for (int i = 0; i < options.per_class; ++i) jobs.push_back({category, i});
    return jobs;
}

}  // namespace

std::vector<std::string> generated_categories() {
    std::vector<std::string> names;
    for (const Category& c : kCategories)
        if (c.paper) names.emplace_back(c.name);
    return names;
}

Mesh generate_shape(const std::string& category, std::uint64_t seed, int index) {
    const Builder build = find_builder(category);
    if (index < 0)
        throw std::invalid_argument("model index must be >= 0, got " + std::to_string(index));
    shapes::Rng rng(shapes::model_seed(seed, category, index));
    shapes::Surface surface = build(rng);
    // Resting on z = 0, centred in x and y.
    const shapes::Vec3 lo = surface.min_corner(), hi = surface.max_corner();
    surface.translate(shapes::Vec3(-0.5 * (lo.x() + hi.x()), -0.5 * (lo.y() + hi.y()), -lo.z()));
    return surface.to_mesh();
}

std::string generated_model_name(const std::string& category, int index) {
    char digits[16];
    std::snprintf(digits, sizeof digits, "%03d", index);
    return "gen_" + category + "_" + digits;
}

std::vector<GeneratedModel> generate_dataset(const GeneratorOptions& options) {
    const std::vector<Job> jobs = plan(options);
    std::vector<GeneratedModel> models(jobs.size());
    parallel_for(jobs.size(), options.threads, [&](std::size_t i) {
        models[i] = {jobs[i].category, generated_model_name(jobs[i].category, jobs[i].index),
                     generate_shape(jobs[i].category, options.seed, jobs[i].index)};
    });
    return models;
}

std::vector<GeneratedFile> write_dataset(const std::string& dir, const GeneratorOptions& options,
                                         const GenerateProgress& progress) {
    const std::vector<Job> jobs = plan(options);
    namespace fs = std::filesystem;
    for (const Job& job : jobs) {
        if (job.index != 0) continue;
        const fs::path folder = fs::path(dir) / job.category;
        std::error_code error;
        fs::create_directories(folder, error);
        if (error || !fs::is_directory(folder))
            throw IoError(file_message(
                folder.string(), 0,
                "cannot create directory" + (error ? ": " + error.message() : std::string())));
    }
    std::vector<GeneratedFile> files(jobs.size());
    std::mutex mutex;
    std::size_t done = 0;
    parallel_for(jobs.size(), options.threads, [&](std::size_t i) {
        const Job& job = jobs[i];
        const Mesh mesh = generate_shape(job.category, options.seed, job.index);
        GeneratedFile& file = files[i];
        file.category = job.category;
        file.name = generated_model_name(job.category, job.index);
        file.path = (fs::path(dir) / job.category / (file.name + ".ply")).string();
        file.vertices = mesh.vertices.size();
        file.triangles = mesh.triangles.size();
        file.extent = mesh.max_corner() - mesh.min_corner();
        write_ply_mesh(file.path, mesh);
        if (progress) {
            const std::lock_guard lock(mutex);
            progress(++done, jobs.size());
        }
    });
    return files;
}

}  // namespace esf
