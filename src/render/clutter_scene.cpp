// Generated cluttered table scenes (esf/render/clutter_scene.hpp): the objects laid out on the
// table (clutter_layout.cpp), a camera above the table, the table, floor and maybe a wall around
// them, the frame rendered with the sensor model, and each object's visible share from renders
// without noise.

#include "esf/render/clutter_scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/splitmix64.hpp"
#include "esf/render/render.hpp"
#include "esf/render/view_sphere.hpp"
#include "render/clutter_geometry.hpp"
#include "render/clutter_layout.hpp"

namespace esf {

namespace {

using detail::analyse;
using detail::Body;
using detail::ClutterRandom;
using detail::Vec2;

// Keys that separate the random streams of one scene.
constexpr std::uint64_t kLayoutKey = 0x6c61796f7574ull;  // "layout"
constexpr std::uint64_t kNoiseKey = 0x6e6f697365ull;     // "noise"

Mesh quad(const Eigen::Vector3d& corner, const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    Mesh mesh;
    const std::array<Eigen::Vector3d, 4> corners = {corner, corner + u, corner + u + v, corner + v};
    for (const Eigen::Vector3d& p : corners) mesh.vertices.push_back(p.cast<float>());
    mesh.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
    return mesh;
}

std::uint32_t pack_rgb(int r, int g, int b) {
    return (static_cast<std::uint32_t>(r) << 16) | (static_cast<std::uint32_t>(g) << 8) |
           static_cast<std::uint32_t>(b);
}

constexpr std::array<std::array<int, 3>, 12> kPalette = {{{200, 60, 50},
                                                          {60, 120, 200},
                                                          {230, 190, 40},
                                                          {70, 160, 80},
                                                          {150, 80, 170},
                                                          {240, 130, 40},
                                                          {40, 170, 170},
                                                          {210, 90, 150},
                                                          {120, 90, 60},
                                                          {160, 200, 60},
                                                          {90, 90, 200},
                                                          {200, 200, 200}}};

}  // namespace

ClutterComposer::ClutterComposer(std::vector<ClutterModel> models, ClutterOptions options)
    : impl_(std::make_unique<Impl>()) {
    if (models.empty()) throw std::invalid_argument("scene composer: no models");
    options.camera.validate();
    const auto check_range = [](double lo, double hi, double min, double max, const char* what) {
        if (!(std::isfinite(lo) && std::isfinite(hi) && lo >= min && lo <= hi && hi <= max))
            throw std::invalid_argument(std::string("scene composer: ") + what + " must satisfy " +
                                        std::to_string(min) +
                                        " <= min <= max <= " + std::to_string(max));
    };
    check_range(options.min_distance, options.max_distance, 0.1, 10.0, "camera distance");
    check_range(options.min_elevation, options.max_elevation, 1.0, 89.0, "camera elevation");
    check_range(options.wall_share, options.wall_share, 0.0, 1.0, "wall share");
    check_range(options.edge_share, options.edge_share, 0.0, 1.0, "edge share");
    if (!(options.size_spread >= 0.0 && options.size_spread <= kClutterMaxSizeSpread))
        throw std::invalid_argument("scene composer: size spread must be in [0, " +
                                    std::to_string(kClutterMaxSizeSpread) + "], got " +
                                    std::to_string(options.size_spread));
    if (options.types.empty()) options.types = clutter_types();
    impl_->shapes.reserve(models.size());
    for (std::size_t m = 0; m < models.size(); ++m) {
        const std::string name =
            models[m].file.empty() ? "model " + std::to_string(m) : models[m].file;
        check_mesh(models[m].mesh, name);
        const double radius = models[m].mesh.bounding_radius();
        if (!(radius > 1e-4 && radius < 2.0))
            throw std::invalid_argument(name + ": bounding radius " + std::to_string(radius) +
                                        " m is not the size of an object on a table");
        impl_->shapes.push_back(analyse(models[m].mesh));
        impl_->categories.push_back(models[m].category);
    }
    std::sort(impl_->categories.begin(), impl_->categories.end());
    impl_->categories.erase(std::unique(impl_->categories.begin(), impl_->categories.end()),
                            impl_->categories.end());
    impl_->models = std::move(models);
    impl_->options = std::move(options);
}

ClutterComposer::~ClutterComposer() = default;
ClutterComposer::ClutterComposer(ClutterComposer&&) noexcept = default;
ClutterComposer& ClutterComposer::operator=(ClutterComposer&&) noexcept = default;

const std::vector<ClutterModel>& ClutterComposer::models() const { return impl_->models; }
const ClutterOptions& ClutterComposer::options() const { return impl_->options; }
bool ClutterComposer::round(std::size_t model) const { return impl_->shapes.at(model).round; }
bool ClutterComposer::boxy(std::size_t model) const { return impl_->shapes.at(model).boxy; }

ClutterType ClutterComposer::type_of(std::size_t index) const {
    return impl_->options.types[index % impl_->options.types.size()];
}

ClutterScene ClutterComposer::compose(std::size_t index) const {
    const ClutterOptions& o = impl_->options;
    const std::uint64_t scene_seed = detail::mix64(o.seed ^ detail::mix64(index + 1));
    ClutterRandom random(scene_seed ^ kLayoutKey);
    ClutterScene scene;
    scene.type = type_of(index);

    const double azimuth = random.uniform(0.0, 2.0 * std::numbers::pi);
    const double elevation =
        random.uniform(o.min_elevation, o.max_elevation) * std::numbers::pi / 180.0;
    const double distance = random.uniform(o.min_distance, o.max_distance);
    const std::vector<Body> bodies = impl_->layout(random, scene.type, azimuth);

    // The objects' extent on the table, and the camera looking at their middle.
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector2d hi = -lo;
    double top = 0.0;
    for (const Body& b : bodies) {
        for (const Vec2& v : b.hull) {
            lo = lo.cwiseMin(v.cast<double>());
            hi = hi.cwiseMax(v.cast<double>());
        }
        top = std::max(top, b.zmax);
    }
    if (bodies.empty()) lo = hi = Eigen::Vector2d::Zero();
    const Eigen::Vector2d middle = 0.5 * (lo + hi);
    const Eigen::Vector3d toward(std::cos(elevation) * std::cos(azimuth),
                                 std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    const Eigen::Vector3d target(middle.x() + random.uniform(-0.03, 0.03),
                                 middle.y() + random.uniform(-0.03, 0.03), 0.3 * top);
    scene.world_to_camera = look_at(target + distance * toward, target);

    // Table (axis-aligned in the world), floor below it, maybe a wall behind the objects.
    std::vector<Mesh> surroundings;
    std::vector<std::uint32_t> surrounding_labels;
    Eigen::Vector2d table_lo =
        lo - Eigen::Vector2d(random.uniform(0.3, 0.7), random.uniform(0.3, 0.7));
    Eigen::Vector2d table_hi =
        hi + Eigen::Vector2d(random.uniform(0.3, 0.7), random.uniform(0.3, 0.7));
    scene.table_edge = random.chance(o.edge_share);
    if (scene.table_edge) {
        const auto side = random.below(4);
        const double margin = random.uniform(0.02, 0.15);
        if (side == 0) table_lo.x() = lo.x() - margin;
        if (side == 1) table_hi.x() = hi.x() + margin;
        if (side == 2) table_lo.y() = lo.y() - margin;
        if (side == 3) table_hi.y() = hi.y() + margin;
    }
    surroundings.push_back(quad(Eigen::Vector3d(table_lo.x(), table_lo.y(), 0.0),
                                Eigen::Vector3d(table_hi.x() - table_lo.x(), 0.0, 0.0),
                                Eigen::Vector3d(0.0, table_hi.y() - table_lo.y(), 0.0)));
    surrounding_labels.push_back(kClutterTableLabel);
    const double floor_half = 6.0;
    surroundings.push_back(quad(
        Eigen::Vector3d(middle.x() - floor_half, middle.y() - floor_half, -kClutterTableHeight),
        Eigen::Vector3d(2.0 * floor_half, 0.0, 0.0), Eigen::Vector3d(0.0, 2.0 * floor_half, 0.0)));
    surrounding_labels.push_back(0);
    scene.wall = random.chance(o.wall_share);
    if (scene.wall) {
        // Behind the objects as the camera sees them, facing it (within 30 degrees).
        const double facing = azimuth + random.uniform(-0.5, 0.5);
        const Eigen::Vector2d normal(std::cos(facing), std::sin(facing));
        double behind = 0.0;
        for (const Body& b : bodies)
            for (const Vec2& v : b.hull)
                behind = std::max(behind, -(v.cast<double>() - middle).dot(normal));
        const Eigen::Vector2d at = middle - (behind + random.uniform(0.02, 0.3)) * normal;
        const Eigen::Vector2d along(-normal.y(), normal.x());
        const double half = 4.0;
        surroundings.push_back(
            quad(Eigen::Vector3d(at.x() - half * along.x(), at.y() - half * along.y(),
                                 -kClutterTableHeight),
                 Eigen::Vector3d(2.0 * half * along.x(), 2.0 * half * along.y(), 0.0),
                 Eigen::Vector3d(0.0, 0.0, kClutterTableHeight + 1.5)));
        surrounding_labels.push_back(0);
    }

    // Objects of another size than their models' are rendered from scaled copies.
    std::vector<Mesh> sized(bodies.size());
    std::vector<SceneObject> objects;
    for (std::size_t i = 0; i < bodies.size(); ++i) {
        const Body& b = bodies[i];
        const Mesh* mesh = &impl_->models[b.model].mesh;
        if (b.size != 1.0) {
            sized[i] = scaled_mesh(*mesh, b.size);
            mesh = &sized[i];
        }
        objects.push_back({mesh, b.pose});
    }
    for (const Mesh& m : surroundings) objects.push_back({&m, Eigen::Isometry3d::Identity()});

    SceneOptions render;
    render.camera = o.camera;
    render.threads = 1;
    render.max_depth = 4.5;  // the Kinect's range
    render.noise = o.noise;
    render.seed = scene_seed ^ kNoiseKey;
    scene.cloud = render_scene(objects, scene.world_to_camera, render);

    // Visible shares: the clean frame against each object alone.
    render.noise = SensorNoise::kNone;
    const std::vector<std::size_t> clean_counts = [&] {
        const PointCloud clean = render_scene(objects, scene.world_to_camera, render);
        std::vector<std::size_t> counts(objects.size(), 0);
        for (const std::uint32_t label : clean.labels)
            if (label >= kSceneLabelFirstObject) ++counts[label - kSceneLabelFirstObject];
        return counts;
    }();
    std::vector<std::size_t> pixels(objects.size(), 0);
    for (const std::uint32_t label : scene.cloud.labels)
        if (label >= kSceneLabelFirstObject) ++pixels[label - kSceneLabelFirstObject];

    const std::uint64_t palette_shift = random.below(kPalette.size());
    for (std::size_t i = 0; i < bodies.size(); ++i) {
        ClutterObject object;
        object.model = bodies[i].model;
        object.object_id = kClutterFirstObjectId + static_cast<std::uint32_t>(i);
        Eigen::Matrix4d scale = Eigen::Matrix4d::Identity();
        scale.topLeftCorner<3, 3>() *= impl_->models[bodies[i].model].scale * bodies[i].size;
        object.pose = (scene.world_to_camera * bodies[i].pose).matrix() * scale;
        object.size = bodies[i].size;
        object.placement = bodies[i].placement;
        object.pixels = pixels[i];
        object.labelled = pixels[i] >= kClutterMinLabelledPixels;
        if (clean_counts[i] > 0) {
            const PointCloud alone = render_scene({&objects[i], 1}, scene.world_to_camera, render);
            std::size_t seen = 0;
            for (const std::uint32_t label : alone.labels) seen += label >= kSceneLabelFirstObject;
            object.visible = seen ? std::min(1.0, static_cast<double>(clean_counts[i]) /
                                                      static_cast<double>(seen))
                                  : 0.0;
        }
        scene.objects.push_back(std::move(object));
    }

    // Labels in the database's convention, and flat colours.
    scene.cloud.rgb.assign(scene.cloud.labels.size(), 0);
    for (std::size_t p = 0; p < scene.cloud.labels.size(); ++p) {
        const std::uint32_t label = scene.cloud.labels[p];
        if (label < kSceneLabelFirstObject) continue;
        const std::size_t k = label - kSceneLabelFirstObject;
        if (k < bodies.size()) {
            const auto& c = kPalette[(k + palette_shift) % kPalette.size()];
            scene.cloud.rgb[p] = pack_rgb(c[0], c[1], c[2]);
            scene.cloud.labels[p] =
                scene.objects[k].labelled ? kClutterLabelDivisor * scene.objects[k].object_id : 0;
            continue;
        }
        const std::uint32_t surrounding = surrounding_labels[k - bodies.size()];
        scene.cloud.labels[p] = surrounding;
        scene.cloud.rgb[p] = surrounding == kClutterTableLabel ? pack_rgb(181, 139, 96)
                             : k - bodies.size() == 1          ? pack_rgb(110, 110, 115)
                                                               : pack_rgb(225, 222, 212);
    }
    return scene;
}

}  // namespace esf
