#pragma once
// Procedural training models: parametric, randomised, watertight meshes of the ten categories of
// the paper's Cat10 set (Wohlkinger & Vincze 2011, Sec. V: apple, banana, bottle, bowl, car,
// donut, hammer, mug, tetra_pak, toilet_paper), so that esf trains without downloading a CAD
// database; and, named on request, wide tins as `can` models (12-22 cm across, the sizes that
// scanned can sets lack), to add to a database of scanned models.
//
// Every model is in metres, +z up, standing (or lying) in its natural resting pose on z = 0,
// centred in x and y. Each model is a union of closed components (a mug is its body and its
// handle, a car its body, cabin and four wheels): every edge of a component is shared by
// exactly two triangles of opposite orientation and normals face outwards. Components may
// overlap, which a depth renderer does not see. Triangle counts lie between about 1k and 20k.
//
// Model `index` of a category comes from its own generator seeded by (seed, category, index):
// the same seed gives bit-identical vertices for any thread count (the random draws themselves
// do not depend on the standard library; only libm rounding could differ between platforms),
// and the first N models of a larger set are the N models of a smaller one.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "esf/mesh/mesh.hpp"

namespace esf {

/// The paper's ten generated categories in alphabetical order: apple, banana, bottle, bowl, car,
/// donut, hammer, mug, tetra_pak, toilet_paper. `can` (wide tins) is generated only when named.
std::vector<std::string> generated_categories();

/// Model `index` (>= 0) of `category`. Throws std::invalid_argument for an unknown category or a
/// negative index.
Mesh generate_shape(const std::string& category, std::uint64_t seed, int index);

/// The file stem of model `index` of a category: "gen_<category>_<index, 3 digits or more>".
std::string generated_model_name(const std::string& category, int index);

struct GeneratorOptions {
    int per_class = 10;  ///< models per category, >= 1
    std::uint64_t seed = 0;
    std::vector<std::string> categories;  ///< to generate (the ten, or `can`); empty = the ten
    int threads = 0;                      ///< 0 = all cores
};

struct GeneratedModel {
    std::string category;
    std::string name;  ///< generated_model_name(category, index)
    Mesh mesh;
};

/// All models, category by category (in the order of options.categories, or alphabetical), each
/// by index. Throws std::invalid_argument for per_class < 1, an unknown or repeated category or a
/// negative thread count.
std::vector<GeneratedModel> generate_dataset(const GeneratorOptions& options);

/// What write_dataset wrote for one model.
struct GeneratedFile {
    std::string category;
    std::string name;
    std::string path;  ///< <dir>/<category>/<name>.ply
    std::size_t vertices = 0;
    std::size_t triangles = 0;
    Eigen::Vector3f extent = Eigen::Vector3f::Zero();  ///< bounding box size, metres
};

/// Called as models are written: (done, total). Calls are serialised but may come from worker
/// threads.
using GenerateProgress = std::function<void(std::size_t, std::size_t)>;

/// Generates the models of generate_dataset(options) and writes each as a binary PLY
/// <dir>/<category>/<name>.ply (directories created, each file written atomically), without
/// holding all meshes in memory. Returns the files in generate_dataset's order. Throws
/// std::invalid_argument as generate_dataset, esf::IoError naming the path when a directory or
/// file cannot be written.
std::vector<GeneratedFile> write_dataset(const std::string& dir, const GeneratorOptions& options,
                                         const GenerateProgress& progress = {});

}  // namespace esf
