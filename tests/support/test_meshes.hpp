#pragma once
// Meshes of known geometry for tests: a box (with or without a knob) and a closed cylinder
// standing on z = 0, centred on the z axis, wound counter-clockwise seen from outside (or clockwise
// on request).

#include <cmath>
#include <numbers>

#include "esf/mesh/mesh.hpp"

namespace esf::test {

/// The box [-sx/2, sx/2] x [-sy/2, sy/2] x [0, sz]: eight corners, twelve triangles.
inline Mesh standing_box(double sx, double sy, double sz, bool clockwise = false) {
    Mesh mesh;
    for (int i = 0; i < 8; ++i)
        mesh.vertices.emplace_back(static_cast<float>((i & 1 ? 0.5 : -0.5) * sx),
                                   static_cast<float>((i & 2 ? 0.5 : -0.5) * sy),
                                   static_cast<float>(i & 4 ? sz : 0.0));
    const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) {
        if (clockwise) {
            mesh.triangles.emplace_back(f[0], f[2], f[1]);
            mesh.triangles.emplace_back(f[0], f[3], f[2]);
        } else {
            mesh.triangles.emplace_back(f[0], f[1], f[2]);
            mesh.triangles.emplace_back(f[0], f[2], f[3]);
        }
    }
    return mesh;
}

/// standing_box(sx, sy, sz) with a cube of side k standing out of its +y face near its +x end,
/// at mid height: a shape that no turn maps onto itself.
inline Mesh knobbed_box(double sx, double sy, double sz, double k) {
    Mesh mesh = standing_box(sx, sy, sz);
    const Mesh knob = standing_box(k, k, k);
    const int base = static_cast<int>(mesh.vertices.size());
    const Eigen::Vector3f at(static_cast<float>(0.5 * sx - 0.75 * k),
                             static_cast<float>(0.5 * sy + 0.5 * k),
                             static_cast<float>(0.5 * sz - 0.5 * k));
    for (const Eigen::Vector3f& v : knob.vertices) mesh.vertices.push_back(v + at);
    for (const Eigen::Vector3i& t : knob.triangles)
        mesh.triangles.push_back(t + Eigen::Vector3i::Constant(base));
    return mesh;
}

/// A closed cylinder of radius r and height h: a `sides`-gon prism with both caps.
inline Mesh standing_cylinder(double r, double h, int sides = 48) {
    Mesh mesh;
    for (int ring = 0; ring < 2; ++ring)
        for (int i = 0; i < sides; ++i) {
            const double a = 2.0 * std::numbers::pi * i / sides;
            mesh.vertices.emplace_back(static_cast<float>(r * std::cos(a)),
                                       static_cast<float>(r * std::sin(a)),
                                       static_cast<float>(ring * h));
        }
    mesh.vertices.emplace_back(0.0f, 0.0f, 0.0f);
    mesh.vertices.emplace_back(0.0f, 0.0f, static_cast<float>(h));
    const int bottom = 2 * sides, top = 2 * sides + 1;
    for (int i = 0; i < sides; ++i) {
        const int j = (i + 1) % sides;
        mesh.triangles.emplace_back(i, j, sides + j);
        mesh.triangles.emplace_back(i, sides + j, sides + i);
        mesh.triangles.emplace_back(bottom, j, i);
        mesh.triangles.emplace_back(top, sides + i, sides + j);
    }
    return mesh;
}

}  // namespace esf::test
