// Rendering the shared real meshes (a KIT and a YCB model) as training does, checked against
// what must hold by construction: every point lies on the mesh under its view's pose (brute
// force over the triangles), on a pixel's ray inside the image; the pose is a rotation times the
// scale that puts the camera on its view sphere direction, looking at the model's centre with
// the image up along the model's +z; the sensor model only moves depths along their rays.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "esf/mesh/mesh.hpp"
#include "esf/render/render.hpp"
#include "esf/render/view_sphere.hpp"
#include "support/test_data.hpp"

namespace {

/// A triangle in file units with its bounding sphere (for a lower bound on the distance).
struct Triangle {
    Eigen::Vector3d a, b, c, centre;
    double radius = 0.0;
};

std::vector<Triangle> triangles_of(const esf::Mesh& mesh) {
    std::vector<Triangle> out;
    for (const auto& t : mesh.triangles) {
        Triangle tri;
        tri.a = mesh.vertices[static_cast<std::size_t>(t[0])].cast<double>();
        tri.b = mesh.vertices[static_cast<std::size_t>(t[1])].cast<double>();
        tri.c = mesh.vertices[static_cast<std::size_t>(t[2])].cast<double>();
        tri.centre = (tri.a + tri.b + tri.c) / 3.0;
        tri.radius = std::max({(tri.a - tri.centre).norm(), (tri.b - tri.centre).norm(),
                               (tri.c - tri.centre).norm()});
        out.push_back(tri);
    }
    return out;
}

/// Distance from p to the closest point of triangle abc (Ericson, Real-Time Collision
/// Detection, 5.1.5: the Voronoi regions of the corners, edges and face in turn).
double distance_to_triangle(const Eigen::Vector3d& p, const Triangle& t) {
    const Eigen::Vector3d ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0.0 && d2 <= 0.0) return ap.norm();
    const Eigen::Vector3d bp = p - t.b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0.0 && d4 <= d3) return bp.norm();
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return (p - (t.a + d1 / (d1 - d3) * ab)).norm();
    const Eigen::Vector3d cp = p - t.c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0.0 && d5 <= d6) return cp.norm();
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return (p - (t.a + d2 / (d2 - d6) * ac)).norm();
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0)
        return (p - (t.b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (t.c - t.b))).norm();
    const double denominator = 1.0 / (va + vb + vc);
    return (p - (t.a + ab * (vb * denominator) + ac * (vc * denominator))).norm();
}

/// Distance from p to the mesh: every triangle, skipping those whose bounding sphere lies
/// farther than the best distance so far.
double distance_to_mesh(const Eigen::Vector3d& p, const std::vector<Triangle>& triangles) {
    double best = std::numeric_limits<double>::infinity();
    for (const Triangle& t : triangles) {
        if ((p - t.centre).norm() - t.radius >= best) continue;
        best = std::min(best, distance_to_triangle(p, t));
    }
    return best;
}

/// Every view of `mesh` rendered with `options` (which has the sensor noise on), against the
/// oracles above; every `stride`-th point of each exact view is measured against the mesh.
void expect_views_on_the_mesh(const esf::Mesh& mesh, const esf::RenderOptions& options,
                              std::size_t views, std::size_t min_points, std::size_t stride) {
    const std::vector<esf::RenderedView> noisy = esf::render_views(mesh, options);
    ASSERT_EQ(noisy.size(), views);
    for (const auto& view : noisy) EXPECT_GT(view.points.size(), min_points) << view.index;

    esf::RenderOptions exact_options = options;
    exact_options.noise = esf::SensorNoise::kNone;
    const esf::MeshRenderer exact(mesh, exact_options);
    ASSERT_EQ(exact.view_count(), views);
    const std::vector<Triangle> triangles = triangles_of(mesh);
    const std::vector<Eigen::Vector3d> directions = esf::view_sphere(options.level);
    const esf::CameraIntrinsics& c = options.camera;
    const double s = exact.scale(), d = exact.camera_distance();
    for (std::size_t i = 0; i < views; ++i) {
        const esf::RenderedView view = exact.render_view(i);
        SCOPED_TRACE("view " + std::to_string(view.index));
        ASSERT_EQ(view.index, noisy[i].index);
        ASSERT_EQ(view.pose, noisy[i].pose);  // the noise moves no camera

        // The pose: scale times a rotation, the camera at the view's direction from the
        // centre at the camera distance, looking at the centre, image up along model +z.
        const Eigen::Matrix4d pose = view.pose.cast<double>();
        const Eigen::Matrix3d r = pose.topLeftCorner<3, 3>() / s;
        EXPECT_LT((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 1e-5);
        EXPECT_NEAR(r.determinant(), 1.0, 1e-5);
        const Eigen::Vector3d t = pose.topRightCorner<3, 1>();
        const Eigen::Vector3d centre_in_camera = s * r * exact.centre() + t;
        EXPECT_LT((centre_in_camera - Eigen::Vector3d(0, 0, d)).norm(), 1e-5 * d);
        const Eigen::Vector3d eye = -r.transpose() * t / s;  // file units
        const Eigen::Vector3d direction = directions[static_cast<std::size_t>(view.index)];
        EXPECT_LT((eye - (exact.centre() + d / s * direction)).norm(), 1e-5 * d / s);
        if (std::abs(direction.z()) < 0.98) {
            EXPECT_NEAR(r(0, 2), 0.0, 1e-5);  // the image x axis is level
            EXPECT_LT(r(1, 2), 0.0);          // image down (+y) points down the model
        }

        // Every point: in front of the camera, on a pixel's ray inside the image, on the mesh.
        const Eigen::Matrix4d to_model = pose.inverse();
        std::unordered_map<long, double> depth_of_pixel;
        for (std::size_t k = 0; k < view.points.size(); ++k) {
            const Eigen::Vector3d p = view.points[k].cast<double>();
            ASSERT_GT(p.z(), 0.0);
            const double u = c.fx * p.x() / p.z() + c.cx, v = c.fy * p.y() / p.z() + c.cy;
            ASSERT_NEAR(u, std::round(u), 1e-3);
            ASSERT_NEAR(v, std::round(v), 1e-3);
            ASSERT_TRUE(u > -0.5 && u < c.width - 0.5 && v > -0.5 && v < c.height - 0.5);
            depth_of_pixel[std::lround(v) * c.width + std::lround(u)] = p.z();
            if (k % stride != 0) continue;
            const Eigen::Vector3d q = (to_model * p.homogeneous()).head<3>();
            ASSERT_LT(s * distance_to_mesh(q, triangles), 1e-5)
                << "point " << k << " is not on the mesh";
        }
        ASSERT_EQ(depth_of_pixel.size(), view.points.size());  // one point per pixel

        // The sensor model drops pixels and moves depths along their rays: every noisy point
        // lies on a pixel of the exact view; the depths scatter about the exact ones without bias,
        // most within 5 mm (more at grazing angles).
        std::size_t near = 0;
        double shift = 0.0;
        for (const auto& point : noisy[i].points) {
            const Eigen::Vector3d p = point.cast<double>();
            const double u = c.fx * p.x() / p.z() + c.cx, v = c.fy * p.y() / p.z() + c.cy;
            ASSERT_NEAR(u, std::round(u), 1e-3);
            ASSERT_NEAR(v, std::round(v), 1e-3);
            const auto it = depth_of_pixel.find(std::lround(v) * c.width + std::lround(u));
            ASSERT_NE(it, depth_of_pixel.end()) << "a noisy point where the mesh is not seen";
            near += std::abs(p.z() - it->second) < 0.005 ? 1 : 0;
            shift += p.z() - it->second;
        }
        EXPECT_LE(noisy[i].points.size(), view.points.size());
        EXPECT_GE(near, noisy[i].points.size() * 90 / 100);
        EXPECT_LT(std::abs(shift) / static_cast<double>(noisy[i].points.size()), 0.001);
    }
}

TEST(RenderRealData, KitAndYcbMeshesGiveEveryView) {
    ESF_REQUIRE_DATA("meshes/bottle/kit_BathDetergent.obj");
    ESF_REQUIRE_DATA("meshes/can/ycb_005_tomato_soup_can.ply");
    // KIT: half the triangles face inwards, 45 mm middle side; rescaled to 0.2 m.
    const esf::Mesh kit =
        esf::load_mesh(esf::test::data_file("meshes/bottle/kit_BathDetergent.obj").string());
    esf::RenderOptions options;
    options.target_extent = 0.2;
    expect_views_on_the_mesh(kit, options, 80, 5000, 13);

    const esf::Mesh can =
        esf::load_mesh(esf::test::data_file("meshes/can/ycb_005_tomato_soup_can.ply").string());
    options = {};
    options.level = 0;
    options.camera = esf::CameraIntrinsics::pcl_renderer();
    expect_views_on_the_mesh(can, options, 20, 500, 5);
}

}  // namespace
