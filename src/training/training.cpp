#include "esf/training/training.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "core/csv.hpp"
#include "core/fnv1a.hpp"
#include "core/splitmix64.hpp"
#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/mesh/model_surface.hpp"
#include "esf/render/occluded_view.hpp"
#include "esf/training/descriptor_settings.hpp"

namespace esf {

namespace fs = std::filesystem;

namespace {

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

bool hidden(const fs::path& p) {
    const auto name = p.filename().string();
    return name.empty() || name.front() == '.';
}

using detail::mix64;

/// Longest sides (metres) of typical household objects, for categories whose catalog has no
/// metric model to learn a size from.
const std::map<std::string, double>& typical_extents() {
    static const std::map<std::string, double> table = {
        {"apple", 0.08},        {"ball", 0.10},         {"banana", 0.19},    {"block", 0.06},
        {"bottle", 0.25},       {"bowl", 0.16},         {"box", 0.18},       {"can", 0.11},
        {"clamp", 0.15},        {"cup", 0.09},          {"cutlery", 0.20},   {"donut", 0.10},
        {"drill", 0.20},        {"figurine", 0.10},     {"fruit", 0.08},     {"glass", 0.12},
        {"hammer", 0.33},       {"mug", 0.11},          {"pitcher", 0.22},   {"plate", 0.25},
        {"scissors", 0.20},     {"screwdriver", 0.20},  {"spray", 0.20},     {"tetra_pak", 0.20},
        {"toilet_paper", 0.12}, {"toy_airplane", 0.25}, {"toy_brick", 0.06}, {"toy_car", 0.12},
        {"tube", 0.17},         {"wrench", 0.20},
    };
    return table;
}

// ---- training -------------------------------------------------------------------------------

/// The descriptor and its options, as the registry takes them (descriptor_settings.hpp).
DescriptorSetup descriptor_setup(const TrainingOptions& options) {
    return {options.descriptor, options.esf, options.descriptor_options};
}

void validate(const TrainingOptions& options) {
    if (options.min_points < 3)
        throw std::invalid_argument("min_points must be >= 3 (ESF needs a triangle), got " +
                                    std::to_string(options.min_points));
    if (options.occlusions > kMaxTrainingOcclusions)
        throw std::invalid_argument("occlusions must be at most " +
                                    std::to_string(kMaxTrainingOcclusions) + ", got " +
                                    std::to_string(options.occlusions));
    if (options.surface_points > kMaxModelSurfacePoints)
        throw std::invalid_argument("surface points must be at most " +
                                    std::to_string(kMaxModelSurfacePoints) + ", got " +
                                    std::to_string(options.surface_points));
    resolve_threads(options.threads);
    // Throws std::invalid_argument: an unknown descriptor (the message lists the valid names)
    // or options out of range; then a baseline's module must load.
    check_descriptor_setup(descriptor_setup(options));
    require_descriptor(options.descriptor);
    // The renderer checks its options (level, camera, noise, fill, scale) when built: build one
    // for a tetrahedron so that bad options fail now, not as a failure of every model.
    Mesh tetrahedron;
    tetrahedron.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    tetrahedron.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    RenderOptions render = options.render;
    render.distance.reset();  // depends on the model's size, checked per model
    render.max_distance.reset();
    MeshRenderer probe(tetrahedron, render);
    if (options.render.distance &&
        !(std::isfinite(*options.render.distance) && *options.render.distance > 0.0))
        throw std::invalid_argument("camera distance must be positive and finite");
    if (options.render.max_distance &&
        !(std::isfinite(*options.render.max_distance) && *options.render.max_distance > 0.0))
        throw std::invalid_argument("largest camera distance must be positive and finite");
}

/// Whether views draw their distance from a range (RenderOptions::max_distance).
bool distance_range(const RenderOptions& r) {
    return r.distance && r.max_distance && *r.max_distance > *r.distance;
}

/// A real setting, or "none" when unset.
SettingValue optional_value(const std::optional<double>& value) {
    return value ? SettingValue(*value) : SettingValue(std::string("none"));
}

SettingValue seed_value(std::uint64_t seed) {
    if (seed <= static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
        return static_cast<std::int64_t>(seed);
    return std::to_string(seed);
}

/// Throws when the database was made with other settings, naming every difference.
void check_settings(const Database& db, const Settings& wanted) {
    const Settings stored = db.settings();
    // Another descriptor: say so first, not only as one difference among many.
    const auto stored_descriptor = stored.find("descriptor");
    const auto wanted_descriptor = wanted.find("descriptor");
    if (stored_descriptor != stored.end() && wanted_descriptor != wanted.end() &&
        stored_descriptor->second != wanted_descriptor->second)
        throw std::invalid_argument(
            file_message(db.path(), 0,
                         "database holds " + to_string(stored_descriptor->second) +
                             " descriptors, not " + to_string(wanted_descriptor->second) +
                             " (setting descriptor " + to_string(wanted_descriptor->second) +
                             ", database: " + to_string(stored_descriptor->second) +
                             "); train each descriptor into its own database, or descriptor " +
                             to_string(stored_descriptor->second) + " to resume this one"));
    std::string differences;
    auto add = [&](const std::string& text) {
        differences += (differences.empty() ? "" : ", ") + text;
    };
    // Settings added later: a database from before them was trained with these values.
    const Settings legacy = {
        {"camera_max_distance", std::string("none")},
        {"camera_min_elevation", -90.0},
        {"camera_max_elevation", 90.0},
        {"occlusions", std::int64_t{0}},
    };
    // Models added from another folder (generated tins) take the catalog the database was
    // trained with, which their folder lacks.
    std::string hint;
    for (const auto& [key, value] : wanted) {
        const auto it = stored.find(key);
        const auto old = legacy.find(key);
        if (it == stored.end() && old != legacy.end() && old->second == value) continue;
        if (it == stored.end()) {
            add(key + " " + to_string(value) + " (database: unset)");
        } else if (it->second != value) {
            add(key + " " + to_string(value) + " (database: " + to_string(it->second) + ")");
            if (key == "rescale_non_metric")
                hint =
                    " (models from another folder: pass --catalog with the catalog it was "
                    "trained with)";
        }
    }
    for (const auto& [key, value] : stored)
        if (!wanted.count(key)) add(key + " unset (database: " + to_string(value) + ")");
    if (!differences.empty())
        throw std::invalid_argument(file_message(
            db.path(), 0,
            "database was trained with other settings: " + differences +
                "; train with the same options to resume, or into a new database" + hint));
}

/// A model being trained: its inputs, its renderer, then the entry to store.
struct Job {
    const PlannedModel* plan = nullptr;
    const ModelFile* file = nullptr;
    std::uint64_t seed = 0;
    std::unique_ptr<MeshRenderer> renderer;
    ModelEntry entry;
};

/// Loads the mesh and builds its renderer; a failure marks the model failed.
void prepare_job(Job& job, const TrainingOptions& options) {
    job.entry.category = job.file->category;
    job.entry.name = job.file->name;
    job.entry.file = job.file->file;
    job.entry.group = job.plan->group;
    try {
        const Mesh mesh = load_mesh(job.file->path);
        RenderOptions render = options.render;
        render.seed = job.seed;
        if (job.plan->rescale) {
            render.scale = job.plan->scale(mesh);
            render.target_extent.reset();
        }
        if (render.distance) {
            // Stand back from a model too large to be seen whole from the given distance.
            const double extent =
                static_cast<double>((mesh.max_corner() - mesh.min_corner()).maxCoeff());
            const double radius =
                mesh.bounding_radius() *
                (render.target_extent ? *render.target_extent / extent : render.scale);
            if (*render.distance < kTrainingMinDistanceFactor * radius) {
                const double factor = kTrainingMinDistanceFactor * radius / *render.distance;
                render.distance = kTrainingMinDistanceFactor * radius;
                if (render.max_distance) *render.max_distance *= factor;
            }
        }
        job.renderer = std::make_unique<MeshRenderer>(mesh, render);
        job.entry.scale = job.renderer->scale();
        if (options.surface_points > 0)
            job.entry.surface =
                sample_model_surface(mesh, job.entry.scale, options.surface_points, job.seed);
        job.entry.views.resize(job.renderer->view_count());
    } catch (const std::exception& e) {
        const std::string what = e.what();
        job.entry.error =
            what.find(job.file->path) == std::string::npos ? job.file->path + ": " + what : what;
        job.renderer.reset();
        job.entry.views.clear();
        job.entry.surface.reset();
    }
}

/// Renders view `v` of a job and describes it with `setup` (or records why it is skipped).
void describe_view(Job& job, std::size_t v, const TrainingOptions& options,
                   const DescriptorSetup& setup) {
    ViewEntry& view = job.entry.views[v];
    view.index = job.renderer->view_index(v);
    RenderedView rendered;
    try {
        rendered = job.renderer->render_view(v);
    } catch (const std::exception& e) {
        view.skip_reason = std::string("rendering failed: ") + e.what();
        return;
    }
    view.index = rendered.index;
    view.points = rendered.points.size();
    view.pose = rendered.pose;
    if (view.points < options.min_points) {
        view.skip_reason = "too few points (" + std::to_string(view.points) + " < " +
                           std::to_string(options.min_points) + ")";
        return;
    }
    // Seeded descriptors (esf, esf-angles, sdvs, d2) draw from the view's seed; one object per
    // view (cheap next to describing it), the others ignore the seed.
    const auto descriptor = make_descriptor(setup, view_seed(job.seed, rendered.index));
    std::vector<Signature> signatures;
    try {
        signatures = descriptor->compute(rendered.points);
    } catch (const std::invalid_argument& e) {
        view.skip_reason = e.what();
        return;
    } catch (const std::runtime_error& e) {  // PCL's exceptions
        view.skip_reason = descriptor->info().name + ": " + e.what();
        return;
    }
    const auto dim = static_cast<std::size_t>(descriptor->info().dimension);
    for (const Signature& s : signatures) {
        if (s.size() != dim) {  // a broken descriptor: refuse the view rather than store it
            view.descriptors.clear();
            view.skip_reason = descriptor->info().name + ": a signature of " +
                               std::to_string(s.size()) + " floats, expected " +
                               std::to_string(dim);
            return;
        }
        view.descriptors.insert(view.descriptors.end(), s.begin(), s.end());
    }
    if (view.descriptors.empty()) {
        view.skip_reason = descriptor->info().name + ": no signature";
        return;
    }
    // Occluded copies: more signatures of the same view, after its own (for a descriptor of one
    // signature a cloud; those of several have none). A copy too small or too degenerate to
    // describe adds none.
    const std::size_t copies = descriptor->info().multi_signature ? 0 : options.occlusions;
    for (std::uint32_t copy = 0; copy < copies; ++copy) {
        const OcclusionEdge edge = occlusion_edge(view_seed(job.seed, rendered.index), copy);
        try {
            const Points hidden = occlude_view(rendered.points, edge.angle, edge.fraction);
            if (hidden.size() < options.min_points) continue;
            for (const Signature& s : descriptor->compute(hidden))
                if (s.size() == dim)
                    view.descriptors.insert(view.descriptors.end(), s.begin(), s.end());
        } catch (const std::invalid_argument&) {
        } catch (const std::runtime_error&) {  // PCL's exceptions
        }
    }
}

}  // namespace

const std::vector<std::string>& mesh_extensions() {
    static const std::vector<std::string> extensions = {"ply", "obj", "off", "stl", "gltf",
                                                        "glb", "dae", "3ds", "fbx"};
    return extensions;
}

std::vector<ModelFile> find_models(const std::string& root) {
    std::error_code ec;
    if (!fs::is_directory(root, ec))
        throw IoError(
            file_message(root, 0, fs::exists(root, ec) ? "not a folder" : "no such folder"));
    const auto& extensions = mesh_extensions();
    std::vector<ModelFile> out;
    try {
        for (const auto& category : fs::directory_iterator(root)) {
            // A folder that cannot be followed (a symbolic link loop) holds no category.
            std::error_code category_ec;
            if (hidden(category.path()) || !category.is_directory(category_ec)) continue;
            for (const auto& entry : fs::directory_iterator(category.path())) {
                // A mesh name that cannot be followed (a symbolic link loop, a dangling link)
                // is listed: loading it fails and training records why, then goes on.
                std::error_code entry_ec;
                const bool regular = entry.is_regular_file(entry_ec);
                if (hidden(entry.path()) || (!regular && !entry_ec)) continue;
                auto ext = lower(entry.path().extension().string());
                if (ext.size() < 2) continue;
                ext.erase(0, 1);
                if (std::find(extensions.begin(), extensions.end(), ext) == extensions.end())
                    continue;
                ModelFile m;
                m.category = category.path().filename().string();
                m.name = entry.path().stem().string();
                m.file = m.category + "/" + entry.path().filename().string();
                m.path = entry.path().string();
                out.push_back(std::move(m));
            }
        }
    } catch (const fs::filesystem_error& e) {
        throw IoError(file_message(e.path1().string(), 0, e.code().message()));
    }
    std::sort(out.begin(), out.end(), [](const ModelFile& a, const ModelFile& b) {
        return std::tie(a.category, a.name, a.file) < std::tie(b.category, b.name, b.file);
    });
    for (std::size_t i = 1; i < out.size(); ++i)
        if (out[i].category == out[i - 1].category && out[i].name == out[i - 1].name)
            throw std::invalid_argument(
                file_message(root, 0,
                             "two meshes share the model name '" + out[i].category + "/" +
                                 out[i].name + "': " + out[i - 1].file + " and " + out[i].file));
    return out;
}

const CatalogEntry* Catalog::find(const std::string& file) const {
    for (const auto& e : entries)
        if (e.file == file) return &e;
    return nullptr;
}

Catalog read_catalog(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(file_message(path, 0, "cannot open catalog"));
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw IoError(file_message(path, 0, "read failed"));
    const std::vector<detail::CsvRecord> records = detail::parse_csv(text, path);
    if (records.empty())
        throw IoError(file_message(path, 0, "empty catalog (expected a header line)"));
    std::map<std::string, std::size_t> column;
    for (std::size_t i = 0; i < records[0].fields.size(); ++i)
        column[detail::lower(detail::trim(records[0].fields[i]))] = i;
    if (!column.count("file")) throw IoError(file_message(path, 1, "header has no 'file' column"));
    const std::size_t columns = records[0].fields.size();
    Catalog catalog;
    for (std::size_t r = 1; r < records.size(); ++r) {
        const std::vector<std::string>& fields = records[r].fields;
        const std::size_t record_line = records[r].line;
        auto get = [&](const char* name) -> std::string {
            const auto it = column.find(name);
            return it == column.end() ? std::string() : detail::trim(fields[it->second]);
        };
        if (fields.size() != columns)
            throw IoError(file_message(path, record_line,
                                       std::to_string(fields.size()) + " fields, the header has " +
                                           std::to_string(columns)));
        CatalogEntry e;
        e.file = get("file");
        if (e.file.empty()) throw IoError(file_message(path, record_line, "empty 'file'"));
        e.category = get("category");
        e.group = get("group");
        const std::string extent = get("extent");
        if (!extent.empty()) {
            std::size_t used = 0;
            try {
                e.extent = std::stod(extent, &used);
            } catch (const std::exception&) {
                used = 0;
            }
            if (used != extent.size() || !std::isfinite(e.extent) || e.extent < 0.0)
                throw IoError(
                    file_message(path, record_line, "extent '" + extent + "' is not a size"));
        }
        const std::string metric = lower(get("metric"));
        if (metric == "no" || metric == "false" || metric == "0") {
            e.metric = false;
        } else if (!(metric.empty() || metric == "yes" || metric == "true" || metric == "1")) {
            throw IoError(
                file_message(path, record_line, "metric '" + metric + "' is not yes or no"));
        }
        catalog.entries.push_back(std::move(e));
    }
    return catalog;
}

double typical_extent(const Catalog& catalog, const std::string& category) {
    std::vector<double> extents;
    for (const auto& e : catalog.entries) {
        const auto slash = e.file.find('/');
        const std::string c = e.category.empty() ? e.file.substr(0, slash) : e.category;
        if (e.metric && e.extent > 0.0 && c == category) extents.push_back(e.extent);
    }
    if (!extents.empty()) {
        std::sort(extents.begin(), extents.end());
        const std::size_t n = extents.size();
        return n % 2 ? extents[n / 2] : 0.5 * (extents[n / 2 - 1] + extents[n / 2]);
    }
    const auto& table = typical_extents();
    const auto it = table.find(category);
    return it == table.end() ? kDefaultTypicalExtent : it->second;
}

std::uint64_t model_seed(std::uint64_t seed, const std::string& category, const std::string& name) {
    return mix64(seed ^ mix64(detail::fnv1a(category + "/" + name)));
}

std::uint64_t view_seed(std::uint64_t model_seed_value, int view_index) {
    return mix64(model_seed_value +
                 detail::kGoldenGamma * (static_cast<std::uint64_t>(view_index) + 1));
}

namespace {

// The catalog a run reads: `catalog`, or ROOT/catalog.csv when it exists; empty for none.
std::string catalog_path(const std::string& root, const std::string& catalog, bool use_catalog) {
    if (!use_catalog) return {};
    if (!catalog.empty()) return catalog;
    const fs::path beside = fs::path(root) / "catalog.csv";
    return fs::exists(beside) ? beside.string() : std::string{};
}

// FNV-1a of a name, mixed: the order groups are dealt into folds.
std::uint64_t group_hash(const std::string& name) { return detail::mix64(detail::fnv1a(name)); }

}  // namespace

void parse_fold(const std::string& text, GroupSelection& selection) {
    const auto slash = text.find('/');
    int k = -1, n = -1;
    try {
        std::size_t used_k = 0, used_n = 0;
        if (slash != std::string::npos) {
            k = std::stoi(text.substr(0, slash), &used_k);
            n = std::stoi(text.substr(slash + 1), &used_n);
            if (used_k != slash || used_n != text.size() - slash - 1) k = n = -1;
        }
    } catch (const std::exception&) {
        k = n = -1;
    }
    if (n < 2 || n > 100 || k < 0 || k >= n)
        throw std::invalid_argument("bad fold '" + text +
                                    "': expected K/N with 0 <= K < N and 2 <= N <= 100");
    selection.fold = k;
    selection.folds = n;
}

double PlannedModel::scale(const Mesh& mesh, double metric_scale) const {
    if (!rescale) return metric_scale;
    double e = extent;
    if (!(e > 0.0)) e = static_cast<double>((mesh.max_corner() - mesh.min_corner()).maxCoeff());
    if (!(e > 0.0) || !std::isfinite(e))
        throw std::invalid_argument(file.path + ": mesh has no extent to rescale");
    return target_extent / e;
}

std::vector<PlannedModel> plan_models(const std::string& root, const std::string& catalog_file,
                                      bool use_catalog, const GroupSelection& selection) {
    const std::vector<ModelFile> files = find_models(root);
    if (files.empty())
        throw std::invalid_argument(file_message(
            root, 0, "no meshes found (expected ROOT/<category>/<model>.ply, .obj, .off, ...)"));
    const std::string path = catalog_path(root, catalog_file, use_catalog);
    const Catalog catalog = path.empty() ? Catalog{} : read_catalog(path);

    std::vector<PlannedModel> plans;
    for (const ModelFile& f : files) {
        PlannedModel plan;
        plan.file = f;
        plan.group = f.name;
        if (const CatalogEntry* entry = catalog.find(f.file)) {
            if (!entry->group.empty()) plan.group = entry->group;
            if (!entry->metric) {
                plan.rescale = true;
                plan.extent = entry->extent;
                plan.target_extent = typical_extent(catalog, f.category);
            }
        }
        plans.push_back(std::move(plan));
    }
    if (selection.empty()) return plans;

    for (const auto* names : {&selection.only, &selection.except})
        for (const std::string& name : *names)
            if (std::none_of(plans.begin(), plans.end(),
                             [&](const PlannedModel& p) { return p.group == name; }))
                throw std::invalid_argument("no group '" + name + "' among the models of " + root);
    for (const std::string& name : selection.categories)
        if (std::none_of(plans.begin(), plans.end(),
                         [&](const PlannedModel& p) { return p.file.category == name; }))
            throw std::invalid_argument("no category '" + name + "' among the models of " + root);
    if (selection.folds > 1 && (selection.fold < 0 || selection.fold >= selection.folds))
        throw std::invalid_argument("fold " + std::to_string(selection.fold) + " is not in [0, " +
                                    std::to_string(selection.folds) + ")");

    // Each category's groups, in hash order, dealt round-robin into the folds.
    std::map<std::string, int> fold_of;
    if (selection.folds > 1) {
        std::map<std::string, std::vector<std::string>> groups_of;
        for (const PlannedModel& p : plans) groups_of[p.file.category].push_back(p.group);
        for (auto& [category, groups] : groups_of) {
            std::sort(groups.begin(), groups.end());
            groups.erase(std::unique(groups.begin(), groups.end()), groups.end());
            if (groups.size() < 2) continue;
            std::sort(groups.begin(), groups.end(), [](const std::string& a, const std::string& b) {
                const std::uint64_t ha = group_hash(a), hb = group_hash(b);
                return ha != hb ? ha < hb : a < b;
            });
            const std::uint64_t start =
                group_hash(category) % static_cast<std::uint64_t>(selection.folds);
            for (std::size_t i = 0; i < groups.size(); ++i)
                fold_of.emplace(groups[i], static_cast<int>((start + i) % selection.folds));
        }
    }
    const auto contains = [](const std::vector<std::string>& list, const std::string& name) {
        return std::find(list.begin(), list.end(), name) != list.end();
    };
    std::vector<PlannedModel> kept;
    for (PlannedModel& p : plans) {
        if (!selection.only.empty() && !contains(selection.only, p.group)) continue;
        if (contains(selection.except, p.group)) continue;
        if (!selection.categories.empty() && !contains(selection.categories, p.file.category))
            continue;
        if (selection.folds > 1) {
            const auto it = fold_of.find(p.group);
            const bool in_fold = it != fold_of.end() && it->second == selection.fold;
            if (in_fold == selection.other_folds) continue;
        }
        kept.push_back(std::move(p));
    }
    if (kept.empty()) throw std::invalid_argument("the group selection leaves no model of " + root);
    return kept;
}

Settings training_settings(const TrainingOptions& options, bool rescale_non_metric) {
    const auto& r = options.render;
    Settings settings = descriptor_settings(descriptor_setup(options));
    Settings common = {
        {"seed", seed_value(options.seed)},
        {"view_sphere_level", std::int64_t{r.level}},
        {"camera_width", std::int64_t{r.camera.width}},
        {"camera_height", std::int64_t{r.camera.height}},
        {"camera_fx", r.camera.fx},
        {"camera_fy", r.camera.fy},
        {"camera_cx", r.camera.cx},
        {"camera_cy", r.camera.cy},
        {"fill_fraction", r.fill_fraction},
        {"camera_distance", optional_value(r.distance)},
        {"camera_max_distance", optional_value(distance_range(r) ? r.max_distance : std::nullopt)},
        {"camera_min_elevation", r.min_elevation},
        {"camera_max_elevation", r.max_elevation},
        {"model_scale", r.scale},
        {"target_extent", optional_value(r.target_extent)},
        {"noise", std::string(to_string(r.noise))},
        {"min_points", static_cast<std::int64_t>(options.min_points)},
        {"occlusions", static_cast<std::int64_t>(options.occlusions)},
        {"rescale_non_metric", std::string(rescale_non_metric ? "category_extent" : "none")},
    };
    settings.merge(common);
    return settings;
}

TrainingResult train(const std::string& root, Database& database, const TrainingOptions& options) {
    validate(options);
    if (!database.writable())
        throw std::invalid_argument(
            file_message(database.path(), 0, "database is opened read-only"));
    const bool have_catalog = !catalog_path(root, options.catalog, options.use_catalog).empty();
    const std::vector<PlannedModel> plans =
        plan_models(root, options.catalog, options.use_catalog, options.groups);

    const Settings settings = training_settings(options, have_catalog);
    if (database.settings().empty() && database.models().empty())
        database.set_settings(settings);
    else
        check_settings(database, settings);
    const DescriptorSetup setup = descriptor_setup(options);
    database.add_descriptor_kind(descriptor_kind(setup));

    TrainingResult result;
    result.models_total = plans.size();
    std::vector<Job> jobs;
    for (const PlannedModel& plan : plans) {
        const ModelFile& f = plan.file;
        if (database.model_status(f.category, f.name) == ModelStatus::kComplete) {
            ++result.models_existing;
            continue;
        }
        Job job;
        job.plan = &plan;
        job.file = &f;
        job.seed = model_seed(options.seed, f.category, f.name);
        jobs.push_back(std::move(job));
    }

    TrainingProgress progress;
    progress.models_total = result.models_total;
    progress.models_existing = result.models_existing;
    progress.models_done = result.models_existing;
    if (options.progress) options.progress(progress);

    // Models go in batches: meshes load and their renderers are built in parallel, then every
    // view of the batch is rendered and described in parallel (one view per task, so large and
    // small models balance), then the models are committed one by one, in order.
    const int threads = resolve_threads(options.threads);
    const std::size_t batch = 2 * static_cast<std::size_t>(threads);
    for (std::size_t first = 0; first < jobs.size(); first += batch) {
        const std::size_t count = std::min(batch, jobs.size() - first);
        parallel_for(count, threads, [&](std::size_t i) { prepare_job(jobs[first + i], options); });

        std::vector<std::pair<std::size_t, std::size_t>> views;  // (job, view)
        for (std::size_t i = first; i < first + count; ++i)
            for (std::size_t v = 0; v < jobs[i].entry.views.size(); ++v) views.emplace_back(i, v);
        parallel_for(views.size(), threads, [&](std::size_t k) {
            describe_view(jobs[views[k].first], views[k].second, options, setup);
        });

        for (std::size_t i = first; i < first + count; ++i) {
            Job& job = jobs[i];
            job.renderer.reset();
            database.write_model(job.entry, setup.name);
            const std::string name = job.entry.category + "/" + job.entry.name;
            if (!job.entry.error.empty()) {
                ++result.models_failed;
                result.failures.push_back({name, job.entry.error});
            } else {
                ++result.models_trained;
                for (const auto& v : job.entry.views) {
                    if (v.skipped())
                        ++result.views_skipped;
                    else
                        ++result.views;
                }
            }
            job.entry = {};
            progress.models_done =
                result.models_existing + result.models_trained + result.models_failed;
            progress.models_failed = result.models_failed;
            progress.views = result.views;
            progress.views_skipped = result.views_skipped;
            progress.model = name;
            if (options.progress) options.progress(progress);
        }
    }
    return result;
}

}  // namespace esf
