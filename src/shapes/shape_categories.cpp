#include "shapes/shape_categories.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace esf::shapes {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kRevolveSegments = 64;

double deg(double degrees) { return degrees * kPi / 180.0; }

/// Samples f(z) for z in [z0, z1] as profile points (f(z), z), `count` points.
template <class F>
Path2 wall(F&& radius_at, double z0, double z1, int count) {
    Path2 path;
    for (int k = 0; k < count; ++k) {
        const double z = lerp(z0, z1, static_cast<double>(k) / (count - 1));
        path.emplace_back(radius_at(z), z);
    }
    return path;
}

/// A smooth periodic wobble sum_k a_k cos(k angle + phase_k), k = 1..3, |value| < total.
struct Wobble {
    std::array<double, 3> amplitude{};
    std::array<double, 3> phase{};

    Wobble(Rng& rng, double total) {
        for (std::size_t k = 0; k < 3; ++k) {
            amplitude[k] = total * rng.uniform(0.0, 1.0) / static_cast<double>(k + 2);
            phase[k] = rng.uniform(0.0, 2.0 * kPi);
        }
    }
    double operator()(double angle) const {
        double sum = 0.0;
        for (std::size_t k = 0; k < 3; ++k)
            sum += amplitude[k] * std::cos(static_cast<double>(k + 1) * angle + phase[k]);
        return sum;
    }
};

/// Circle of `count` points, radius 1.
Path2 circle(int count) { return superellipse(1.0, 1.0, 2.0, count); }

/// Rotation taking the z axis to `axis`.
Eigen::Affine3d z_to(const Vec3& axis) {
    return Eigen::Affine3d(Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), axis.normalized()));
}

/// A closed cap shaped like a bottle or carton screw cap, axis +z, base buried `depth` below 0.
Surface screw_cap(double radius, double height, double depth, int ribs) {
    const double round = std::min(0.0015, 0.3 * height);
    Path2 p;
    extend(p, segment({0.0, -depth}, {radius, -depth}, 4));
    extend(p, segment({radius, -depth}, {radius, height - round}, 5));
    extend(p, arc({radius - round, height - round}, round, 0.0, 0.5 * kPi, 4));
    extend(p, segment({radius - round, height}, {0.0, height}, 4));
    const auto knurl = [=](const Vec3& q, std::size_t, double angle) {
        const double r = q.head<2>().norm();
        if (ribs == 0 || r < 0.98 * radius || q.z() < 0.0 || q.z() > height - round) return q;
        Vec3 out = q;
        out.head<2>() *= 1.0 + 0.035 * std::cos(ribs * angle);
        return out;
    };
    return revolve(p, ribs > 0 ? 2 * ribs : 48, knurl);
}

}  // namespace

// ---- apple: a squashed sphere, wider at the top, with dimples at both poles, lobes and a stem.

Surface make_apple(Rng& rng) {
    const double radius = rng.uniform(0.036, 0.045);
    const double squash = rng.uniform(0.82, 0.97);  // height / width
    const double shoulder = rng.uniform(0.0, 0.12);
    const double top_depth = rng.uniform(0.008, 0.014);
    const double top_width = rng.uniform(0.32, 0.45);
    const double bottom_depth = rng.uniform(0.002, 0.006);
    const double bottom_width = rng.uniform(0.25, 0.40);
    const double lobes = rng.uniform(0.0, 0.035);
    const double lobe_phase = rng.uniform(0.0, 2.0 * kPi);
    const double lean = rng.uniform(0.0, 0.06);
    const double lean_angle = rng.uniform(0.0, 2.0 * kPi);

    constexpr int kCount = 60;
    Path2 profile;
    std::vector<double> polar;  // polar angle of each profile point (0 = top)
    for (int k = 0; k <= kCount; ++k) {
        const double phi = kPi * (1.0 - static_cast<double>(k) / kCount);
        const double r = radius * std::sin(phi) * (1.0 + shoulder * std::cos(phi));
        const double z = radius * squash * std::cos(phi) -
                         top_depth * std::exp(-std::pow(phi / top_width, 2)) +
                         bottom_depth * std::exp(-std::pow((kPi - phi) / bottom_width, 2));
        profile.emplace_back(k == 0 || k == kCount ? 0.0 : r, z);
        polar.push_back(phi);
    }
    const double z_scale = radius * squash;
    const auto deform = [=](const Vec3& q, std::size_t i, double angle) {
        Vec3 out = q;
        const double phi = polar[std::min(i, polar.size() - 1)];
        out.head<2>() *=
            1.0 + lobes * std::cos(5.0 * angle + lobe_phase) * 0.5 * (1.0 - std::cos(phi));
        const double shear = lean * radius * (q.z() / z_scale);
        out.x() += shear * std::cos(lean_angle);
        out.y() += shear * std::sin(lean_angle);
        return out;
    };
    Surface apple = revolve(profile, kRevolveSegments, deform);

    if (rng.chance(0.85)) {
        const Vec3 base = deform(Vec3(0.0, 0.0, profile.back().y()), polar.size() - 1, 0.0);
        const double length = rng.uniform(0.010, 0.022) + top_depth;
        const double stem_r = rng.uniform(0.0015, 0.0022);
        const double tilt = rng.uniform(0.1, 0.45);
        const double azimuth = rng.uniform(0.0, 2.0 * kPi);
        const Vec3 side(std::cos(azimuth), std::sin(azimuth), 0.0);
        std::vector<TubeStation> stations;
        constexpr int kStations = 8;
        for (int k = 0; k <= kStations; ++k) {
            const double t = static_cast<double>(k) / kStations;
            const Vec3 c = base + Vec3(0.0, 0.0, length * t - 0.003) +
                           side * (length * std::sin(tilt) * t * t);
            const double s = stem_r * (k == kStations ? 1.15 : lerp(1.1, 0.85, t));
            stations.push_back({c, s, s});
        }
        apple.append(tube(stations, circle(10), side, 0.0, 0.3));
    }
    return apple;
}

// ---- banana: a curved, tapered tube of rounded-pentagon section with a cut stalk.

Surface make_banana(Rng& rng) {
    const double length = rng.uniform(0.145, 0.215);  // along the spine, stalk excluded
    const double bend = rng.uniform(0.50, 1.40);      // total turn of the spine, radians
    const double skew = rng.uniform(-0.4, 0.9);       // > 0: more curved near the stalk
    const double radius = rng.uniform(0.0150, 0.0210);
    const double peak = rng.uniform(0.35, 0.55);  // where the girth is largest
    const double tip_r = rng.uniform(0.0030, 0.0045);
    const double stalk_len = rng.uniform(0.015, 0.030);
    const double stalk_r = rng.uniform(0.0045, 0.0060);
    const double lift = rng.uniform(0.0, 0.012);   // the ends rise off the table
    const double ridges = rng.uniform(0.35, 0.7);  // 0 = round, 1 = pentagon

    // Spine in the table plane: tangent angle a(s) with curvature bend * (1 - 2 skew (s - 1/2)),
    // integrated numerically (midpoint rule).
    constexpr int kSteps = 512;
    std::vector<Vec2> plane(kSteps + 1, Vec2::Zero());
    for (int k = 0; k < kSteps; ++k) {
        const double s = (k + 0.5) / kSteps - 0.5;
        const double a = bend * (s - skew * (s * s - 1.0 / 12.0));
        plane[static_cast<std::size_t>(k) + 1] =
            plane[static_cast<std::size_t>(k)] + length / kSteps * Vec2(std::cos(a), std::sin(a));
    }
    const auto spine = [&](double s) {
        const double x = std::clamp(s, 0.0, 1.0) * kSteps;
        const auto k = std::min(static_cast<std::size_t>(x), static_cast<std::size_t>(kSteps - 1));
        const Vec2 q = plane[k] + (x - static_cast<double>(k)) * (plane[k + 1] - plane[k]);
        return Vec3(q.x(), q.y(), radius + lift * std::pow(2.0 * s - 1.0, 2));
    };
    const auto girth = [&](double s) {
        const double t = s < peak ? 0.5 * s / peak : 0.5 + 0.5 * (s - peak) / (1.0 - peak);
        const double shape = std::sin(kPi * t);
        return s < peak ? stalk_r + (radius - stalk_r) * std::pow(shape, 0.6)
                        : tip_r + (radius - tip_r) * std::pow(shape, 0.45);
    };

    std::vector<TubeStation> stations;
    const Vec3 start = spine(0.0);
    const Vec3 back = (spine(0.0) - spine(0.01)).normalized();
    constexpr int kStalk = 6;
    for (int k = 0; k < kStalk; ++k) {  // from the cut end to the body
        const double t = 1.0 - static_cast<double>(k) / kStalk;
        const Vec3 c = start + back * (stalk_len * t) + Vec3(0.0, 0.0, 0.25 * stalk_len * t * t);
        const double s = stalk_r * (k == 0 ? 1.2 : 1.0);
        stations.push_back({c, s, s});
    }
    constexpr int kBody = 56;
    for (int k = 0; k <= kBody; ++k) {
        const double s = 0.5 - 0.5 * std::cos(kPi * k / kBody);
        const double g = girth(s);
        stations.push_back({spine(s), g, g});
    }
    // Rounded pentagon: blend of a circle and a regular pentagon (radius 1 at the corners).
    Path2 section;
    constexpr int kSection = 20;
    for (int k = 0; k < kSection; ++k) {
        const double a = 2.0 * kPi * k / kSection;
        const double sector = 2.0 * kPi / 5.0;
        const double local = std::fmod(a, sector) - 0.5 * sector;
        const double pentagon = std::cos(0.5 * sector) / std::cos(local);
        const double r =
            lerp(1.0, pentagon, ridges) / lerp(1.0, std::cos(0.5 * sector), 0.5 * ridges);
        section.emplace_back(r * std::cos(a), r * std::sin(a));
    }
    return tube(stations, section, Vec3::UnitZ(), 0.0, 0.8);
}

// ---- bottle: body (round, square-ish or flat), shoulder, neck with an optional support ring,
// and a screw cap; solid.

Surface make_bottle(Rng& rng) {
    const double height = rng.uniform(0.19, 0.32);
    const double radius = height * rng.uniform(0.105, 0.155);
    const double neck_r = rng.uniform(0.0105, 0.0150);
    const double cap_r = neck_r + rng.uniform(0.0010, 0.0030);
    const double cap_h = rng.uniform(0.012, 0.024);
    const double neck_len = height * rng.uniform(0.05, 0.22);
    const double shoulder_len = height * rng.uniform(0.10, 0.24);
    const double body_top = height - cap_h - neck_len - shoulder_len;
    const double base_round = rng.uniform(0.003, 0.009);
    const double roundness = rng.uniform();  // shoulder: 0 = S-curve, 1 = domed
    const double waist = rng.chance(0.4) ? rng.uniform(0.03, 0.09) : 0.0;
    const double waist_z = body_top * rng.uniform(0.45, 0.65);
    const double exponent = rng.chance(0.35) ? rng.uniform(2.6, 4.0) : 2.0;
    const double aspect = rng.chance(0.25) ? rng.uniform(0.60, 0.85) : 1.0;
    const bool support_ring = rng.chance(0.5);

    const auto body_r = [&](double z) {
        return radius * (1.0 - waist * std::exp(-std::pow((z - waist_z) / (0.12 * body_top), 2)));
    };
    Path2 p;
    extend(p, segment({0.0, 0.0}, {radius - base_round, 0.0}, 6));
    extend(p, arc({radius - base_round, base_round}, base_round, -0.5 * kPi, 0.0, 5));
    extend(p, wall(body_r, base_round, body_top, 26));
    const int shoulder_points = 22;
    for (int k = 1; k < shoulder_points; ++k) {
        const double u = std::sin(0.5 * kPi * k / (shoulder_points - 1));
        const double s_curve = 0.5 * (1.0 + std::cos(kPi * u));
        const double dome = std::sqrt(std::max(0.0, 1.0 - u * u));
        p.emplace_back(neck_r + (radius - neck_r) * lerp(s_curve, dome, roundness),
                       body_top + u * shoulder_len);
    }
    const double neck_top = height - cap_h;
    if (support_ring) {
        const double zr = neck_top - std::min(0.006, 0.5 * neck_len);
        extend(p, segment(p.back(), {neck_r, zr - 0.0012}, 4));
        p.emplace_back(neck_r + 0.003, zr - 0.0008);
        p.emplace_back(neck_r + 0.003, zr + 0.0008);
        p.emplace_back(neck_r, zr + 0.0012);
    }
    extend(p, segment(p.back(), {neck_r, neck_top}, 4));
    const double cap_round = std::min(0.0015, 0.3 * cap_h);
    extend(p, segment({neck_r, neck_top}, {cap_r, neck_top}, 2));
    extend(p, segment({cap_r, neck_top}, {cap_r, height - cap_round}, 5));
    extend(p, arc({cap_r - cap_round, height - cap_round}, cap_round, 0.0, 0.5 * kPi, 4));
    extend(p, segment({cap_r - cap_round, height}, {0.0, height}, 4));

    const double fade_end = body_top + 0.8 * shoulder_len;
    const auto deform = [=](const Vec3& q, std::size_t, double angle) {
        const double w = 1.0 - smoothstep(body_top, fade_end, q.z());
        if (w <= 0.0) return q;
        const double c = std::abs(std::cos(angle)), s = std::abs(std::sin(angle)) / aspect;
        const double rho = std::pow(std::pow(c, exponent) + std::pow(s, exponent), -1.0 / exponent);
        Vec3 out = q;
        out.head<2>() *= lerp(1.0, rho, w);
        return out;
    };
    return revolve(p, kRevolveSegments, deform);
}

// ---- bowl: flared wall of real thickness, rounded rim, recessed foot.

Surface make_bowl(Rng& rng) {
    const double radius = rng.uniform(0.060, 0.105);  // rim, outside
    const double height = std::max(0.045, radius * rng.uniform(0.40, 0.72));
    const double foot_r = radius * rng.uniform(0.35, 0.55);
    const double thickness = rng.uniform(0.003, 0.0055);
    const double recess = rng.chance(0.7) ? rng.uniform(0.002, 0.005) : 0.0;
    const double flare = deg(rng.uniform(55.0, 88.0));
    const double k1 = rng.uniform(0.25, 0.70), k2 = rng.uniform(0.20, 0.55);

    const Vec2 p0(foot_r, 0.0), p3(radius, height);
    const Vec2 p1(foot_r + k1 * (radius - foot_r), 0.0);
    const Vec2 p2 = p3 - k2 * height * Vec2(std::cos(flare), std::sin(flare));
    const Path2 outer = bezier(p0, p1, p2, p3, 44);
    const Path2 inner = offset(outer, thickness);  // left of the upward curve = inside

    Path2 p;
    if (recess > 0.0) {
        const double foot_w = std::min(0.006, 0.3 * foot_r);
        extend(p, segment({0.0, recess}, {foot_r - foot_w, recess}, 8));
        extend(p, segment({foot_r - foot_w, recess}, {foot_r - 0.6 * foot_w, 0.0}, 3));
        extend(p, segment({foot_r - 0.6 * foot_w, 0.0}, p0, 3));
    } else {
        extend(p, segment({0.0, 0.0}, p0, 8));
    }
    extend(p, outer);
    const Vec2 t3 = (p3 - outer[outer.size() - 2]).normalized();
    const Vec2 inward(-t3.y(), t3.x());
    const Vec2 rim_centre = p3 + 0.5 * thickness * inward;
    const double a0 = std::atan2(-inward.y(), -inward.x());
    extend(p, arc(rim_centre, 0.5 * thickness, a0, a0 + kPi, 8));
    // Inner wall from the rim down to the floor, then across to the axis.
    const double floor_z = std::max(recess + 1.2 * thickness, 1.1 * thickness);
    for (std::size_t k = inner.size() - 1; k > 0; --k) {
        const Vec2& a = inner[k];
        const Vec2& b = inner[k - 1];
        if (b.y() > floor_z) {
            extend(p, {a});
            continue;
        }
        const double t = (a.y() - floor_z) / (a.y() - b.y());
        extend(p, {a});
        const Vec2 hit = a + t * (b - a);
        extend(p, segment(hit, {0.0, floor_z}, std::max(3, static_cast<int>(hit.x() / 0.008))));
        break;
    }
    return revolve(p, kRevolveSegments);
}

// ---- can: a wide tin (cookie, biscuit or paint tin), a closed cylinder with rounded rims and,
// on half of them, a lid whose lip stands out from the body. Radius 6-11 cm (log-uniform),
// height 0.3-1 times the diameter: the wide tins that scanned can sets lack (their cans are
// at most 10 cm across); narrow cans are left to the scans.

Surface make_can(Rng& rng) {
    const double radius = std::exp(rng.uniform(std::log(0.060), std::log(0.110)));
    const double height = 2.0 * radius * rng.uniform(0.30, 1.00);
    const double round = std::min({0.08 * radius, 0.004, 0.25 * height});
    const bool lid = rng.chance(0.5);
    const double lip = lid ? rng.uniform(0.001, 0.0025) : 0.0;  // the lid's overhang
    const double lid_h = lid ? std::min(0.3 * height, rng.uniform(0.010, 0.020)) : 0.0;

    Path2 p;
    extend(p, segment({0.0, 0.0}, {radius - round, 0.0}, 8));
    extend(p, arc({radius - round, round}, round, -0.5 * kPi, 0.0, 5));
    if (lid) {
        const double body_top = height - lid_h;
        extend(p, segment({radius, round}, {radius, body_top}, 10));
        extend(p, segment({radius, body_top}, {radius + lip, body_top}, 2));
        extend(p, segment({radius + lip, body_top}, {radius + lip, height - round}, 4));
        extend(p, arc({radius + lip - round, height - round}, round, 0.0, 0.5 * kPi, 5));
        extend(p, segment({radius + lip - round, height}, {0.0, height}, 8));
    } else {
        extend(p, segment({radius, round}, {radius, height - round}, 12));
        extend(p, arc({radius - round, height - round}, round, 0.0, 0.5 * kPi, 5));
        extend(p, segment({radius - round, height}, {0.0, height}, 8));
    }
    return revolve(p, kRevolveSegments);
}

// ---- car: a toy car — body with rounded ends and wheel arches, a cabin, four wheels.

Surface make_car(Rng& rng) {
    const double length = rng.uniform(0.09, 0.18);
    const double width = length * rng.uniform(0.40, 0.48);
    const double wheel_r = length * rng.uniform(0.115, 0.15);
    const double wheel_w = length * rng.uniform(0.07, 0.095);
    const double wheelbase = length * rng.uniform(0.56, 0.64);
    const double axle_shift = length * rng.uniform(-0.03, 0.02);
    const double clearance = wheel_r * rng.uniform(0.45, 0.65);
    const double belt =
        std::max(clearance + length * rng.uniform(0.14, 0.19), 1.5 * wheel_r + 0.05 * length);
    const double end_round =
        std::min(0.45 * (belt - clearance), 0.25 * width) * rng.uniform(0.6, 1.0);
    const double edge_round = length * rng.uniform(0.04, 0.07);
    const double tumblehome = rng.uniform(0.75, 0.9);
    // Body style: sedan (bonnet, cabin, boot), hatchback (cabin to the tail) or van (short
    // bonnet, tall cabin over the whole length).
    const double style = rng.uniform();
    const bool sedan = style < 0.45, van = style >= 0.8;
    const double flush_rear = -(0.5 * length - end_round);
    const double cabin_h = length * (van ? rng.uniform(0.15, 0.21) : rng.uniform(0.10, 0.15));
    const double ws_base = length * (van ? rng.uniform(0.25, 0.32) : rng.uniform(0.05, 0.17));
    const double ws_run = length * (van ? rng.uniform(0.06, 0.12) : rng.uniform(0.08, 0.16));
    const double rear_base = sedan ? -length * rng.uniform(0.22, 0.32) : flush_rear;
    const double rear_run = length * (sedan ? rng.uniform(0.06, 0.12) : rng.uniform(0.0, 0.05));
    const double hood_drop = length * rng.uniform(0.0, 0.035);
    const double tail_drop = sedan ? length * rng.uniform(0.0, 0.025) : 0.0;

    const std::array<double, 2> axles = {axle_shift + 0.5 * wheelbase,
                                         axle_shift - 0.5 * wheelbase};
    const double arch_r = 1.15 * wheel_r, arch_top = 1.45 * wheel_r;
    const auto bottom_at = [&](double x) {
        double z = clearance;
        for (const double axle : axles) {
            const double u = (x - axle) / arch_r;
            if (std::abs(u) < 1.0)
                z = std::max(z, clearance + (arch_top - clearance) * std::pow(1.0 - u * u, 0.35));
        }
        return z;
    };
    const auto top_at = [&](double x) {
        return belt - hood_drop * smoothstep(ws_base, 0.5 * length, x) -
               tail_drop * smoothstep(-rear_base, 0.5 * length, -x);
    };

    Surface car;
    std::vector<Ring> rings;
    constexpr int kStations = 72;
    for (int k = 0; k <= kStations; ++k) {
        const double x = -0.5 * length * std::cos(kPi * k / kStations);
        const double d = std::max(0.0, 0.5 * length - std::abs(x));
        const double e =
            d < end_round
                ? end_round -
                      std::sqrt(std::max(0.0, end_round * end_round - std::pow(end_round - d, 2)))
                : 0.0;
        const double top = top_at(x) - 0.8 * e, bottom = bottom_at(x) + 0.6 * e;
        const double half_y = 0.5 * width - e, half_z = 0.5 * (top - bottom);
        rings.push_back(place(rounded_rect(half_y, half_z, edge_round, 4, 2),
                              Vec3(x, 0.0, 0.5 * (top + bottom)), Vec3::UnitY(), Vec3::UnitZ()));
    }
    car.append(loft(rings));

    // Cabin: horizontal slices between the windscreen and the rear window, roof edges rounded.
    const double cabin_base = belt - 0.015 * length;
    const double roof = belt + cabin_h;
    const double roof_round = std::min(0.35 * cabin_h, length * rng.uniform(0.03, 0.05));
    const double base_half_y = 0.5 * width - 0.6 * edge_round;
    const auto cabin_slice = [&](double z, double inset) {
        const double tau = (z - cabin_base) / (roof - cabin_base);
        const double front = lerp(ws_base, ws_base - ws_run, tau);
        const double rear = lerp(rear_base, rear_base + rear_run, tau);
        const double half_y = lerp(base_half_y, tumblehome * base_half_y, tau);
        return Slice{z,
                     0.5 * (front - rear) - inset,
                     half_y - inset,
                     0.05 * length - inset,
                     0.5 * (front + rear),
                     0.0};
    };
    std::vector<Slice> slices;
    for (int k = 0; k < 4; ++k)
        slices.push_back(cabin_slice(lerp(cabin_base, roof - roof_round, k / 4.0), 0.0));
    for (int k = 0; k <= 4; ++k) {
        const double a = 0.5 * kPi * k / 4;
        slices.push_back(
            cabin_slice(roof - roof_round * (1.0 - std::sin(a)), roof_round * (1.0 - std::cos(a))));
    }
    car.append(stack(slices, 4, 3));

    // Wheels: tyre with rounded shoulders and a recessed hub, axis along y.
    const double hw = 0.5 * wheel_w;
    const double hub_r = wheel_r * rng.uniform(0.5, 0.65);
    const double hub_in = 0.3 * hw;
    const double shoulder = std::min(0.2 * wheel_r, 0.6 * hw);
    Path2 p;
    extend(p, segment({0.0, hw - hub_in}, {hub_r, hw - hub_in}, 3));
    extend(p, segment({hub_r, hw - hub_in}, {hub_r, hw}, 2));
    extend(p, segment({hub_r, hw}, {wheel_r - shoulder, hw}, 3));
    extend(p, arc({wheel_r - shoulder, hw - shoulder}, shoulder, 0.5 * kPi, 0.0, 5));
    extend(p, segment({wheel_r, hw - shoulder}, {wheel_r, -hw + shoulder}, 3));
    extend(p, arc({wheel_r - shoulder, -hw + shoulder}, shoulder, 0.0, -0.5 * kPi, 5));
    extend(p, segment({wheel_r - shoulder, -hw}, {hub_r, -hw}, 3));
    extend(p, segment({hub_r, -hw}, {hub_r, -hw + hub_in}, 2));
    extend(p, segment({hub_r, -hw + hub_in}, {0.0, -hw + hub_in}, 3));
    const Surface wheel = revolve(p, 40);
    const Eigen::Affine3d axis_to_y(Eigen::AngleAxisd(-0.5 * kPi, Vec3::UnitX()));
    for (const double axle : axles) {
        for (const double side : {-1.0, 1.0}) {
            Surface w = wheel;
            w.transform(axis_to_y).translate(Vec3(axle, side * (0.5 * width - 0.6 * hw), wheel_r));
            car.append(w);
        }
    }
    return car;
}

// ---- donut: a torus of flattened, lumpy section.

Surface make_donut(Rng& rng) {
    const double centre_r = rng.uniform(0.026, 0.038);
    const double half_w = std::min(rng.uniform(0.013, 0.022), centre_r - 0.011);  // hole >= 22 mm
    const double half_h = std::min(rng.uniform(0.010, 0.019), 1.1 * half_w);
    const double top_n = rng.uniform(2.0, 2.4), bottom_n = rng.uniform(2.6, 4.0);
    const Wobble ring_wobble(rng, 0.05), width_wobble(rng, 0.12), height_wobble(rng, 0.15);

    constexpr int kCount = 40;
    Path2 section, profile;
    for (int k = 0; k < kCount; ++k) {
        const double a = 2.0 * kPi * k / kCount;
        const double c = std::cos(a), s = std::sin(a);
        const double power = 2.0 / (s >= 0.0 ? top_n : bottom_n);
        section.emplace_back(half_w * std::copysign(std::pow(std::abs(c), power), c),
                             half_h * std::copysign(std::pow(std::abs(s), power), s));
        profile.emplace_back(centre_r + section.back().x(), half_h + section.back().y());
    }
    profile.push_back(profile.front());
    const auto deform = [=](const Vec3&, std::size_t i, double angle) {
        const Vec2& q = section[i % section.size()];
        const double r =
            centre_r * (1.0 + ring_wobble(angle)) + q.x() * (1.0 + width_wobble(angle));
        const double z = half_h + (q.y() > 0.0 ? q.y() * (1.0 + height_wobble(angle)) : q.y());
        return Vec3(r * std::cos(angle), r * std::sin(angle), z);
    };
    return revolve(profile, kRevolveSegments, deform);
}

// ---- hammer: oval wooden handle, head with a striking face and a claw, a ball peen or a
// second face. Built upright (handle along +z, head along x), then laid on its side.

Surface make_hammer(Rng& rng) {
    const double handle_len = rng.uniform(0.24, 0.31);
    const double grip_a = rng.uniform(0.013, 0.017);
    const double grip_b = grip_a * rng.uniform(0.62, 0.80);
    const double neck = rng.uniform(0.70, 0.88);
    const double butt_flare = rng.uniform(1.0, 1.15);
    const double head_h = rng.uniform(0.030, 0.040);  // along the handle
    const double head_w = rng.uniform(0.022, 0.030);  // thickness (y)
    const double eye_half = rng.uniform(0.015, 0.020);
    const double face_len = rng.uniform(0.045, 0.065);
    const double face_r = rng.uniform(0.0125, 0.0160);
    const double neck_r = std::min(face_r * rng.uniform(0.65, 0.85), 0.42 * head_w);
    const int kind = rng.chance(0.6) ? 0 : (rng.chance(0.6) ? 1 : 2);  // claw, ball peen, club

    Surface hammer;
    std::vector<TubeStation> handle;
    constexpr int kHandle = 30;
    for (int k = 0; k <= kHandle; ++k) {
        const double t = static_cast<double>(k) / kHandle;
        double f = 1.0 + 0.06 * std::sin(kPi * std::min(1.0, t / 0.6));  // grip swell
        f *= lerp(1.0, neck, smoothstep(0.45, 0.9, t));
        f *= lerp(butt_flare, 1.0, smoothstep(0.0, 0.08, t));
        handle.push_back({Vec3(0.0, 0.0, handle_len * t), grip_a * f, grip_b * f});
    }
    hammer.append(tube(handle, superellipse(1.0, 1.0, 2.3, 20), Vec3::UnitX(), 0.35, 0.0));

    const double centre_z = handle_len + 0.004 - 0.5 * head_h;
    Surface eye = stack(
        rounded_box_slices(Vec3(eye_half, 0.5 * head_w, 0.5 * head_h + 0.003), 0.003, 0.003, 2));
    eye.translate(Vec3(0.0, 0.0, centre_z - 0.5 * head_h - 0.003));
    hammer.append(eye);

    const auto face = [&](double direction) {  // striking face along direction * x
        std::vector<TubeStation> s;
        constexpr int kFace = 16;
        for (int k = 0; k <= kFace; ++k) {
            const double t = static_cast<double>(k) / kFace;
            // From the eye's section (fits inside the eye block) to the neck, then the face.
            const double neck_in = smoothstep(0.0, 0.35, t), face_out = smoothstep(0.55, 0.92, t);
            double ru = lerp(lerp(0.45 * head_h, neck_r, neck_in), face_r, face_out);
            double rv = lerp(lerp(0.45 * head_w, neck_r, neck_in), face_r, face_out);
            if (k == kFace) ru *= 0.93, rv *= 0.93;  // chamfer
            s.push_back({Vec3(direction * (0.3 * eye_half + (face_len - 0.3 * eye_half) * t), 0.0,
                              centre_z),
                         ru, rv});
        }
        return tube(s, circle(24), Vec3::UnitZ(), 0.0, 0.08);
    };
    hammer.append(face(-1.0));

    if (kind == 0) {  // claw: two curved prongs, tapering, curling towards the handle
        const double claw_r = rng.uniform(0.045, 0.070);
        const double sweep = rng.uniform(0.75, 1.10);
        const double prong_half_w = 0.25 * head_w;
        for (const double side : {-1.0, 1.0}) {
            std::vector<TubeStation> s;
            constexpr int kClaw = 24;
            for (int k = 0; k <= kClaw; ++k) {
                const double t = static_cast<double>(k) / kClaw;
                const double a = sweep * t;
                // The prongs overlap into one wedge at the root and part towards the tips.
                const double half_w = prong_half_w * lerp(1.0, 0.7, t);
                const double gap = lerp(-0.6 * half_w, 0.0015, smoothstep(0.1, 0.6, t));
                const Vec3 c(0.3 * eye_half + claw_r * std::sin(a), side * (half_w + gap),
                             centre_z - claw_r * (1.0 - std::cos(a)));
                s.push_back({c, lerp(0.45 * head_h, 0.0035, t), half_w});
            }
            hammer.append(tube(s, superellipse(1.0, 1.0, 3.0, 16), Vec3::UnitZ(), 0.0, 0.4));
        }
    } else if (kind == 1) {  // ball peen
        const double ball_r = rng.uniform(0.011, 0.015);
        const double reach = rng.uniform(0.035, 0.05);
        std::vector<TubeStation> s;
        for (int k = 0; k <= 10; ++k) {
            const double t = k / 10.0;
            const double w = smoothstep(0.0, 0.6, t);
            s.push_back({Vec3(0.3 * eye_half + (reach - 0.3 * eye_half) * t, 0.0, centre_z),
                         lerp(0.45 * head_h, 0.7 * ball_r, w),
                         lerp(0.45 * head_w, 0.7 * ball_r, w)});
        }
        hammer.append(tube(s, circle(24), Vec3::UnitZ()));
        Path2 ball;
        for (int k = 0; k <= 24; ++k) {
            const double a = kPi * (static_cast<double>(k) / 24 - 0.5);
            ball.emplace_back(k == 0 || k == 24 ? 0.0 : ball_r * std::cos(a), ball_r * std::sin(a));
        }
        Surface b = revolve(ball, 32);
        b.transform(Eigen::Affine3d(Eigen::AngleAxisd(0.5 * kPi, Vec3::UnitY())))
            .translate(Vec3(reach, 0.0, centre_z));
        hammer.append(b);
    } else {  // club: a second face
        hammer.append(face(1.0));
    }
    // Lay it on its side: y (the head's thickness) becomes vertical.
    hammer.transform(Eigen::Affine3d(Eigen::AngleAxisd(0.5 * kPi, Vec3::UnitX())));
    return hammer;
}

// ---- mug: tapered or bellied wall of real thickness, rounded rim, thick floor, D-shaped handle.

Surface make_mug(Rng& rng) {
    const double height = rng.uniform(0.080, 0.115);
    const double r_top = rng.uniform(0.036, 0.047);
    const double r_bottom = r_top * rng.uniform(0.82, 1.04);
    const double belly = rng.uniform(-0.03, 0.06);
    const double thickness = rng.uniform(0.003, 0.006);
    const double floor = rng.uniform(0.006, 0.012);
    const double foot = rng.uniform(0.002, 0.006);
    const double fillet = rng.uniform(0.003, 0.008);

    const auto outer = [&](double z) {
        const double t = z / height;
        return lerp(r_bottom, r_top, t) + r_top * belly * std::sin(kPi * t);
    };
    const auto inner = [&](double z) { return outer(z) - thickness; };
    const double rim_z = height - 0.5 * thickness;
    Path2 p;
    extend(p, segment({0.0, 0.0}, {outer(foot) - foot, 0.0}, 7));
    extend(p, arc({outer(foot) - foot, foot}, foot, -0.5 * kPi, 0.0, 5));
    extend(p, wall(outer, foot, rim_z, 26));
    extend(p, arc({outer(rim_z) - 0.5 * thickness, rim_z}, 0.5 * thickness, 0.0, kPi, 8));
    extend(p, wall(inner, rim_z, floor + fillet, 24));
    const double fillet_x = inner(floor + fillet) - fillet;
    extend(p, arc({fillet_x, floor + fillet}, fillet, 0.0, -0.5 * kPi, 5));
    extend(p, segment({fillet_x, floor}, {0.0, floor}, 7));
    Surface mug = revolve(p, kRevolveSegments);

    // Handle: a tube along a cubic Bezier leaving and entering the wall radially; its ends stop
    // inside the wall so the cavity stays clean.
    const double z_hi = height - rng.uniform(0.010, 0.022);
    const double span = rng.uniform(0.045, std::min(0.072, z_hi - 0.012));
    const double z_lo = z_hi - span;
    const double reach = rng.uniform(0.020, 0.034);
    const double a1 = rng.uniform(0.85, 1.2), a2 = rng.uniform(0.85, 1.2);
    const double half_t = rng.uniform(0.0035, 0.0055);  // in the handle's plane
    const double half_w = rng.uniform(0.0050, 0.0085);  // across it
    const double n = rng.uniform(2.0, 3.0);
    const Vec2 h0(outer(z_hi) - 0.5 * thickness, z_hi), h3(outer(z_lo) - 0.5 * thickness, z_lo);
    const Vec2 h1(outer(z_hi) + 1.33 * reach * a1, z_hi), h2(outer(z_lo) + 1.33 * reach * a2, z_lo);
    std::vector<TubeStation> s;
    for (const Vec2& q : bezier(h0, h1, h2, h3, 40))
        s.push_back({Vec3(q.x(), 0.0, q.y()), half_t, half_w});
    mug.append(tube(s, superellipse(1.0, 1.0, n, 16), Vec3::UnitZ()));
    return mug;
}

// ---- tetra_pak: gable-top carton — rounded-edge box, gable roof, sealed fin, optional cap.

Surface make_tetra_pak(Rng& rng) {
    struct Size {
        double litres, width;
    };
    constexpr std::array<Size, 5> kSizes = {
        {{0.25, 0.0575}, {0.5, 0.0685}, {1.0, 0.0715}, {1.0, 0.0715}, {1.9, 0.0950}}};
    const Size size = kSizes[static_cast<std::size_t>(rng.integer(0, 4))];
    const double width = size.width * rng.uniform(0.96, 1.04);  // across the ridge (x)
    const double depth = width * rng.uniform(0.92, 1.0);        // along the ridge (y)
    // The body holds about 90 % of the nominal volume; the rest is headspace under the gable.
    const double body_h = 0.9 * size.litres * 1e-3 / (width * depth) * rng.uniform(0.95, 1.05);
    const double roof_h = 0.5 * width * std::tan(deg(rng.uniform(30.0, 42.0)));
    const double fin_h = rng.uniform(0.008, 0.013);
    const double fin_half = rng.uniform(0.0012, 0.0020);
    const double corner = rng.uniform(0.002, 0.005);

    std::vector<Slice> s;
    const double hx = 0.5 * width, hy = 0.5 * depth, bevel = 0.0015;
    s.push_back({0.0, hx - bevel, hy - bevel, corner - bevel});
    s.push_back({0.3 * bevel, hx - 0.3 * bevel, hy - 0.3 * bevel, corner - 0.3 * bevel});
    for (int k = 0; k <= 10; ++k) s.push_back({lerp(bevel, body_h, k / 10.0), hx, hy, corner});
    for (int k = 1; k <= 4; ++k) {
        const double t = k / 4.0;
        const double half_x = lerp(hx, fin_half, t);
        s.push_back({body_h + t * roof_h, half_x, hy, std::min(corner, 0.9 * half_x)});
    }
    const double top = body_h + roof_h + fin_h;
    s.push_back({top - 0.0006, fin_half, hy - 0.0003, 0.9 * fin_half});
    s.push_back({top, 0.6 * fin_half, hy - 0.0008, 0.5 * fin_half});
    Surface carton = stack(s, 4, 5);

    const double slope_len = std::hypot(hx - fin_half, roof_h);
    const double cap_r = rng.uniform(0.010, 0.0135);
    if (rng.chance(0.5) && slope_len > 2.0 * cap_r + 0.006) {
        const Vec3 normal = Vec3(roof_h, 0.0, hx - fin_half).normalized();
        const Vec3 on_roof(0.5 * (hx + fin_half), rng.uniform(-0.3, 0.3) * (hy - cap_r),
                           body_h + 0.5 * roof_h);
        Surface cap = screw_cap(cap_r, rng.uniform(0.010, 0.015), 0.004, 24);
        cap.transform(z_to(normal)).translate(on_roof);
        carton.append(cap);
    }
    return carton;
}

// ---- toilet_paper: a hollow roll (torus-like) on a cardboard core, rounded outer edges.

Surface make_toilet_paper(Rng& rng) {
    const double core_r = rng.uniform(0.019, 0.0235);  // inside of the core
    const double core_t = rng.uniform(0.0012, 0.0020);
    const double outer_r = rng.uniform(0.050, 0.064);
    const double height = rng.uniform(0.095, 0.114);
    const double gap = rng.uniform(0.0005, 0.0020);  // paper edge below the core's
    const double round = rng.uniform(0.002, 0.005);
    const double squash = rng.chance(0.3) ? rng.uniform(0.90, 0.98) : 1.0;

    const double r1 = core_r + core_t;
    Path2 p;
    extend(p, segment({core_r, 0.0}, {r1, 0.0}, 2));
    extend(p, segment({r1, 0.0}, {r1, gap}, 2));
    extend(p, segment({r1, gap}, {outer_r - round, gap}, 6));
    extend(p, arc({outer_r - round, gap + round}, round, -0.5 * kPi, 0.0, 5));
    extend(p, segment({outer_r, gap + round}, {outer_r, height - gap - round}, 14));
    extend(p, arc({outer_r - round, height - gap - round}, round, 0.0, 0.5 * kPi, 5));
    extend(p, segment({outer_r - round, height - gap}, {r1, height - gap}, 6));
    extend(p, segment({r1, height - gap}, {r1, height}, 2));
    extend(p, segment({r1, height}, {core_r, height}, 2));
    extend(p, segment({core_r, height}, {core_r, 0.0}, 14));
    const auto deform = [=](const Vec3& q, std::size_t, double) {
        return Vec3(q.x(), q.y() * squash, q.z());
    };
    return revolve(p, 72, deform);
}

}  // namespace esf::shapes
