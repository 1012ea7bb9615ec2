// Generated cluttered table scenes (esf/render/clutter_scene.hpp): placement on the table by
// footprints (2-D convex hulls of each posed model), a camera above the table, the frame rendered
// with the sensor model, and each object's visible share from renders without noise.

#include "esf/render/clutter_scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/convex_hull_2d.hpp"
#include "core/splitmix64.hpp"
#include "esf/render/render.hpp"
#include "esf/render/view_sphere.hpp"
#include "render/clutter_geometry.hpp"

namespace esf {

namespace {

using detail::analyse;
using detail::Body;
using detail::collide;
using detail::ModelShape;
using detail::rotation_about;
using detail::Vec2;

// Keys that separate the random streams of one scene.
constexpr std::uint64_t kLayoutKey = 0x6c61796f7574ull;  // "layout"
constexpr std::uint64_t kNoiseKey = 0x6e6f697365ull;     // "noise"

class Random {
  public:
    explicit Random(std::uint64_t seed) : mixer_(seed) {}
    double uniform() { return mixer_.uniform(); }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    std::size_t below(std::size_t n) { return mixer_.below(n); }
    int between(int lo, int hi) {
        return lo + static_cast<int>(below(static_cast<std::size_t>(hi - lo + 1)));
    }
    bool chance(double p) { return uniform() < p; }

  private:
    detail::SplitMix64 mixer_;
};

}  // namespace

struct ClutterComposer::Impl {
    std::vector<ClutterModel> models;
    ClutterOptions options;
    std::vector<ModelShape> shapes;
    std::vector<std::string> categories;  // sorted, distinct

    // A model whose shape passes `accept` (any model when none does): a category first, evenly,
    // then one of its models, so that categories with many models do not fill every scene.
    template <class Accept>
    std::size_t pick_model(Random& random, Accept accept) const {
        std::vector<std::vector<std::size_t>> by_category(categories.size());
        for (std::size_t m = 0; m < models.size(); ++m) {
            if (!accept(m)) continue;
            const auto it =
                std::lower_bound(categories.begin(), categories.end(), models[m].category);
            by_category[static_cast<std::size_t>(it - categories.begin())].push_back(m);
        }
        std::vector<const std::vector<std::size_t>*> present;
        for (const auto& list : by_category)
            if (!list.empty()) present.push_back(&list);
        if (present.empty()) return random.below(models.size());
        const std::vector<std::size_t>& list = *present[random.below(present.size())];
        return list[random.below(list.size())];
    }

    // The model posed by `rotation` (about its bounding box centre), lowest point on z = 0,
    // footprint centred at the origin.
    Body make_body(std::size_t model, const Eigen::Matrix3d& rotation,
                   const std::string& placement) const {
        Body body;
        body.model = model;
        body.placement = placement;
        const Mesh& mesh = models[model].mesh;
        const Eigen::Vector3d centre =
            (0.5 * (mesh.min_corner() + mesh.max_corner())).cast<double>();
        body.pose.linear() = rotation;
        body.pose.translation() = -rotation * centre;
        std::vector<Vec2> xy;
        body.zmin = std::numeric_limits<double>::infinity();
        body.zmax = -body.zmin;
        for (const Eigen::Vector3d& p : shapes[model].support)
            xy.push_back((body.pose * p).head<2>().cast<float>());
        // Heights from every vertex: an object rests exactly on what is below it.
        const Eigen::RowVector3d z_row = body.pose.matrix().row(2).head<3>();
        for (const Eigen::Vector3f& v : mesh.vertices) {
            const double z = z_row.dot(v.cast<double>()) + body.pose.translation().z();
            body.zmin = std::min(body.zmin, z);
            body.zmax = std::max(body.zmax, z);
        }
        body.hull = detail::convex_hull(xy);
        Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
        Eigen::Vector2d hi = -lo;
        for (const Vec2& v : body.hull) {
            lo = lo.cwiseMin(v.cast<double>());
            hi = hi.cwiseMax(v.cast<double>());
        }
        const Eigen::Vector2d mid = 0.5 * (lo + hi);
        body.move(Eigen::Vector3d(-mid.x(), -mid.y(), -body.zmin));
        body.radius = 0.0;
        for (const Vec2& v : body.hull)
            body.radius = std::max(body.radius, (v.cast<double>() - body.centre).norm());
        return body;
    }

    // Upright (or, with `lying`, on its side) at a random yaw.
    Body random_body(Random& random, std::size_t model, double lying_share) const {
        const double yaw = random.uniform(0.0, 2.0 * std::numbers::pi);
        Eigen::Matrix3d base = Eigen::Matrix3d::Identity();
        std::string placement = "standing";
        if (random.chance(lying_share)) {
            base = rotation_about(
                random.chance(0.5) ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY(),
                0.5 * std::numbers::pi);
            placement = "lying";
        }
        return make_body(model, rotation_about(Eigen::Vector3d::UnitZ(), yaw) * base, placement);
    }

    double lying_share(std::size_t model) const {
        if (shapes[model].boxy) return 0.3;
        if (shapes[model].round) return 0.1;
        return 0.15;
    }

    static bool free(const Body& body, const std::vector<Body>& bodies, double gap,
                     int except = -1) {
        for (std::size_t i = 0; i < bodies.size(); ++i)
            if (static_cast<int>(i) != except && static_cast<int>(i) != body.base &&
                collide(body, bodies[i], gap))
                return false;
        return true;
    }

    // Somewhere in a disc around the origin, at least `gap` from every other body.
    bool place_apart(Random& random, Body& body, const std::vector<Body>& bodies, double radius,
                     double gap) const {
        for (int round = 0; round < 8; ++round, radius *= 1.2) {
            for (int attempt = 0; attempt < 40; ++attempt) {
                const double r = radius * std::sqrt(random.uniform());
                const double a = random.uniform(0.0, 2.0 * std::numbers::pi);
                const Eigen::Vector2d target(r * std::cos(a), r * std::sin(a));
                body.move(Eigen::Vector3d(target.x() - body.centre.x(),
                                          target.y() - body.centre.y(), 0.0));
                if (free(body, bodies, gap)) return true;
            }
        }
        return false;
    }

    // Slid from `anchor`'s centre (offset sideways by `side`) along `angle` until it no longer
    // overlaps the anchor, then `gap` further.
    static void slide_from(Body& body, const Body& anchor, double angle, double side, double gap) {
        const Eigen::Vector2d dir(std::cos(angle), std::sin(angle));
        const Eigen::Vector2d start = anchor.centre + side * Eigen::Vector2d(-dir.y(), dir.x());
        const auto put = [&](double t) {
            const Eigen::Vector2d at = start + t * dir;
            body.move(Eigen::Vector3d(at.x() - body.centre.x(), at.y() - body.centre.y(), 0.0));
        };
        double lo = 0.0, hi = anchor.radius + body.radius + std::abs(side) + 0.01;
        for (int i = 0; i < 30; ++i) {
            const double mid = 0.5 * (lo + hi);
            put(mid);
            (collide(body, anchor, 0.0) ? lo : hi) = mid;
        }
        put(hi + gap);
    }

    // Touching one of `bodies` (on the table), no closer than 1 mm to the others.
    bool place_touching(Random& random, Body& body, const std::vector<Body>& bodies, double max_gap,
                        double tilt_deg = 0.0) const {
        const Body original = body;
        for (int attempt = 0; attempt < 60; ++attempt) {
            const auto anchor = random.below(bodies.size());
            if (bodies[anchor].base >= 0) continue;  // beside what stands on the table
            const double angle = random.uniform(0.0, 2.0 * std::numbers::pi);
            body = original;
            if (tilt_deg > 0.0) {
                // Leans towards the anchor: its top moves along -u.
                const Eigen::Vector3d u(std::cos(angle), std::sin(angle), 0.0);
                const Eigen::Matrix3d tilt = rotation_about(u.cross(Eigen::Vector3d::UnitZ()),
                                                            tilt_deg * std::numbers::pi / 180.0);
                body = make_body(body.model, tilt * original.pose.linear(), "leaning");
            }
            slide_from(body, bodies[anchor], angle, 0.0, random.uniform(0.0, max_gap));
            if (free(body, bodies, 0.001, static_cast<int>(anchor))) return true;
        }
        body = original;
        return false;
    }

    // On the top of `base`, its centre within the base's top.
    bool place_on(Random& random, Body& body, const std::vector<Body>& bodies,
                  std::size_t base) const {
        const Body& under = bodies[base];
        body.base = static_cast<int>(base);
        body.placement = "stacked";
        for (int attempt = 0; attempt < 20; ++attempt) {
            const double reach = 0.3 * std::max(0.0, under.radius - 0.5 * body.radius);
            const double a = random.uniform(0.0, 2.0 * std::numbers::pi);
            const double r = reach * std::sqrt(random.uniform());
            const Eigen::Vector2d at = under.centre + r * Eigen::Vector2d(std::cos(a), std::sin(a));
            body.move(Eigen::Vector3d(at.x() - body.centre.x(), at.y() - body.centre.y(),
                                      under.zmax - body.zmin));
            if (detail::inside_convex(under.hull, body.centre.cast<float>()) &&
                free(body, bodies, 0.001))
                return true;
        }
        return false;
    }

    // Between `target` and the camera (azimuth `towards`), hiding part of it.
    bool place_in_front(Random& random, Body& body, const std::vector<Body>& bodies,
                        std::size_t target, double towards) const {
        for (int attempt = 0; attempt < 40; ++attempt) {
            const double angle = towards + random.uniform(-0.35, 0.35);
            const double side = random.uniform(-0.6, 0.6) * bodies[target].radius;
            slide_from(body, bodies[target], angle, side, random.uniform(0.01, 0.08));
            if (free(body, bodies, 0.005)) return true;
        }
        return false;
    }

    std::vector<Body> layout(Random& random, ClutterType type, double camera_azimuth) const {
        std::vector<Body> bodies;
        const auto any = [](std::size_t) { return true; };
        const auto round = [&](std::size_t m) { return shapes[m].round; };
        const auto boxy = [&](std::size_t m) { return shapes[m].boxy; };
        const auto add_apart = [&](std::size_t model, double radius, double gap) {
            Body body = random_body(random, model, lying_share(model));
            if (place_apart(random, body, bodies, radius, gap)) bodies.push_back(body);
        };
        const auto add_touching = [&](std::size_t model, double tilt_deg) {
            Body body = random_body(random, model, tilt_deg > 0.0 ? 0.0 : lying_share(model));
            if (bodies.empty()) {
                bodies.push_back(body);
                return;
            }
            if (place_touching(random, body, bodies, 0.004, tilt_deg)) bodies.push_back(body);
        };
        const auto add_on_top = [&](std::size_t model) {
            std::vector<std::size_t> bases;
            for (std::size_t i = 0; i < bodies.size(); ++i)
                if (shapes[bodies[i].model].boxy && bodies[i].placement != "leaning")
                    bases.push_back(i);
            if (bases.empty()) return false;
            Body body = random_body(random, model, shapes[model].boxy ? 0.5 : 0.0);
            if (!place_on(random, body, bodies, bases[random.below(bases.size())])) return false;
            bodies.push_back(body);
            return true;
        };
        switch (type) {
            case ClutterType::kIsolated: {
                const int n = random.between(2, 4);
                for (int i = 0; i < n; ++i)
                    add_apart(pick_model(random, any), 0.06 + 0.05 * n, 0.03);
                break;
            }
            case ClutterType::kTouching: {
                const int n = random.between(2, 5);
                for (int i = 0; i < n; ++i) add_touching(pick_model(random, any), 0.0);
                break;
            }
            case ClutterType::kStacked: {
                const int bases = random.between(1, 2);
                for (int i = 0; i < bases; ++i) {
                    const std::size_t model = pick_model(random, boxy);
                    Body body = random_body(random, model, 0.5);
                    if (place_apart(random, body, bodies, 0.15, 0.05)) bodies.push_back(body);
                }
                const int tops = random.between(1, 2);
                for (int i = 0; i < tops; ++i)
                    add_on_top(random.chance(0.5) ? pick_model(random, boxy)
                                                  : pick_model(random, any));
                const int others = random.between(0, 2);
                for (int i = 0; i < others; ++i) add_apart(pick_model(random, any), 0.2, 0.03);
                break;
            }
            case ClutterType::kOccluded: {
                const int n = random.between(2, 4);
                add_apart(pick_model(random, any), 0.05, 0.0);
                for (int i = 1; i < n && !bodies.empty(); ++i) {
                    const std::size_t model = pick_model(random, any);
                    Body body = random_body(random, model, lying_share(model));
                    if (place_in_front(random, body, bodies, random.below(bodies.size()),
                                       camera_azimuth))
                        bodies.push_back(body);
                }
                break;
            }
            case ClutterType::kCylindric: {
                const int n = random.between(2, 5);
                const bool touching = random.chance(0.5);
                for (int i = 0; i < n; ++i) {
                    const std::size_t model = pick_model(random, round);
                    if (touching)
                        add_touching(model, 0.0);
                    else
                        add_apart(model, 0.06 + 0.04 * n, 0.02);
                }
                break;
            }
            case ClutterType::kMixed: {
                const int n = random.between(5, 7);
                for (int i = 0; i < n; ++i) {
                    const double roll = random.uniform();
                    const std::size_t model = pick_model(random, any);
                    if (i > 0 && roll < 0.45)
                        add_touching(model, 0.0);
                    else if (i > 0 && roll < 0.55 && add_on_top(model))
                        continue;
                    else
                        add_apart(model, 0.25, 0.02);
                }
                break;
            }
            case ClutterType::kComplex: {
                const int n = random.between(10, 18);
                for (int i = 0; i < n; ++i) {
                    const double roll = random.uniform();
                    const std::size_t model = pick_model(random, any);
                    if (i == 0 || roll < 0.15)
                        add_apart(model, 0.3, 0.005);
                    else if (roll < 0.3)
                        add_touching(model, random.uniform(8.0, 20.0));
                    else if (roll < 0.38 && add_on_top(model))
                        continue;
                    else
                        add_touching(model, 0.0);
                }
                break;
            }
        }
        return bodies;
    }
};

namespace {

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
    Random random(scene_seed ^ kLayoutKey);
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

    std::vector<SceneObject> objects;
    for (const Body& b : bodies) objects.push_back({&impl_->models[b.model].mesh, b.pose});
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
        scale.topLeftCorner<3, 3>() *= impl_->models[bodies[i].model].scale;
        object.pose = (scene.world_to_camera * bodies[i].pose).matrix() * scale;
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
