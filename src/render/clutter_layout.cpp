// The layout of a generated table scene (render/clutter_layout.hpp): which models, in which
// poses, where on the table, for each scene type.

#include "render/clutter_layout.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "core/convex_hull_2d.hpp"

namespace esf {

namespace {

using detail::Body;
using detail::ClutterRandom;
using detail::collide;
using detail::rotation_about;
using detail::Vec2;

}  // namespace

template <class Accept>
std::size_t ClutterComposer::Impl::pick_model(ClutterRandom& random, Accept accept) const {
    std::vector<std::vector<std::size_t>> by_category(categories.size());
    for (std::size_t m = 0; m < models.size(); ++m) {
        if (!accept(m)) continue;
        const auto it = std::lower_bound(categories.begin(), categories.end(), models[m].category);
        by_category[static_cast<std::size_t>(it - categories.begin())].push_back(m);
    }
    std::vector<const std::vector<std::size_t>*> present;
    for (const auto& list : by_category)
        if (!list.empty()) present.push_back(&list);
    if (present.empty()) return random.below(models.size());
    const std::vector<std::size_t>& list = *present[random.below(present.size())];
    return list[random.below(list.size())];
}

Body ClutterComposer::Impl::make_body(std::size_t model, const Eigen::Matrix3d& rotation,
                                      const std::string& placement, double size) const {
    Body body;
    body.model = model;
    body.size = size;
    body.placement = placement;
    const Mesh& mesh = models[model].mesh;
    const Eigen::Vector3d centre =
        0.5 * size * (mesh.min_corner() + mesh.max_corner()).cast<double>();
    body.pose.linear() = rotation;
    body.pose.translation() = -rotation * centre;
    std::vector<Vec2> xy;
    body.zmin = std::numeric_limits<double>::infinity();
    body.zmax = -body.zmin;
    for (const Eigen::Vector3d& p : shapes[model].support)
        xy.push_back((body.pose * (size * p)).head<2>().cast<float>());
    // Heights from every vertex: an object rests exactly on what is below it.
    const Eigen::RowVector3d z_row = body.pose.matrix().row(2).head<3>();
    for (const Eigen::Vector3f& v : mesh.vertices) {
        const double z = size * z_row.dot(v.cast<double>()) + body.pose.translation().z();
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

Body ClutterComposer::Impl::random_body(ClutterRandom& random, std::size_t model,
                                        double lying_share) const {
    const double yaw = random.uniform(0.0, 2.0 * std::numbers::pi);
    Eigen::Matrix3d base = Eigen::Matrix3d::Identity();
    std::string placement = "standing";
    if (random.chance(lying_share)) {
        base =
            rotation_about(random.chance(0.5) ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY(),
                           0.5 * std::numbers::pi);
        placement = "lying";
    }
    // Drawn only with a spread, so that scenes without one are those of earlier releases.
    const double spread = std::log1p(options.size_spread);
    const double size = spread > 0.0 ? std::exp(random.uniform(-spread, spread)) : 1.0;
    return make_body(model, rotation_about(Eigen::Vector3d::UnitZ(), yaw) * base, placement, size);
}

double ClutterComposer::Impl::lying_share(std::size_t model) const {
    if (shapes[model].boxy) return 0.3;
    if (shapes[model].round) return 0.1;
    return 0.15;
}

bool ClutterComposer::Impl::free(const Body& body, const std::vector<Body>& bodies, double gap,
                                 int except) {
    for (std::size_t i = 0; i < bodies.size(); ++i)
        if (static_cast<int>(i) != except && static_cast<int>(i) != body.base &&
            collide(body, bodies[i], gap))
            return false;
    return true;
}

bool ClutterComposer::Impl::place_apart(ClutterRandom& random, Body& body,
                                        const std::vector<Body>& bodies, double radius,
                                        double gap) const {
    for (int round = 0; round < 8; ++round, radius *= 1.2) {
        for (int attempt = 0; attempt < 40; ++attempt) {
            const double r = radius * std::sqrt(random.uniform());
            const double a = random.uniform(0.0, 2.0 * std::numbers::pi);
            const Eigen::Vector2d target(r * std::cos(a), r * std::sin(a));
            body.move(
                Eigen::Vector3d(target.x() - body.centre.x(), target.y() - body.centre.y(), 0.0));
            if (free(body, bodies, gap)) return true;
        }
    }
    return false;
}

void ClutterComposer::Impl::slide_from(Body& body, const Body& anchor, double angle, double side,
                                       double gap) {
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

bool ClutterComposer::Impl::place_touching(ClutterRandom& random, Body& body,
                                           const std::vector<Body>& bodies, double max_gap,
                                           double tilt_deg) const {
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
            body = make_body(body.model, tilt * original.pose.linear(), "leaning", body.size);
        }
        slide_from(body, bodies[anchor], angle, 0.0, random.uniform(0.0, max_gap));
        if (free(body, bodies, 0.001, static_cast<int>(anchor))) return true;
    }
    body = original;
    return false;
}

bool ClutterComposer::Impl::place_on(ClutterRandom& random, Body& body,
                                     const std::vector<Body>& bodies, std::size_t base) const {
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

bool ClutterComposer::Impl::place_in_front(ClutterRandom& random, Body& body,
                                           const std::vector<Body>& bodies, std::size_t target,
                                           double towards) const {
    for (int attempt = 0; attempt < 40; ++attempt) {
        const double angle = towards + random.uniform(-0.35, 0.35);
        const double side = random.uniform(-0.6, 0.6) * bodies[target].radius;
        slide_from(body, bodies[target], angle, side, random.uniform(0.01, 0.08));
        if (free(body, bodies, 0.005)) return true;
    }
    return false;
}

std::vector<Body> ClutterComposer::Impl::layout(ClutterRandom& random, ClutterType type,
                                                double camera_azimuth) const {
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
            for (int i = 0; i < n; ++i) add_apart(pick_model(random, any), 0.06 + 0.05 * n, 0.03);
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
                add_on_top(random.chance(0.5) ? pick_model(random, boxy) : pick_model(random, any));
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

}  // namespace esf
