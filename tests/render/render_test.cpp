#include "esf/render/render.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "esf/render/view_sphere.hpp"
#include "support/error_of.hpp"

namespace {

using esf::test::error_of;

/// Axis-aligned box [-sx/2, sx/2] x [-sy/2, sy/2] x [-sz/2, sz/2] + offset, 12 triangles
/// counter-clockwise seen from outside (or inside when `inward`).
esf::Mesh make_box(double sx, double sy, double sz, const Eigen::Vector3d& offset = {0, 0, 0},
                   bool inward = false) {
    esf::Mesh mesh;
    for (int i = 0; i < 8; ++i) {
        const Eigen::Vector3d corner((i & 1) ? sx / 2 : -sx / 2, (i & 2) ? sy / 2 : -sy / 2,
                                     (i & 4) ? sz / 2 : -sz / 2);
        mesh.vertices.push_back((corner + offset).cast<float>());
    }
    // Quads (counter-clockwise from outside) split into two triangles each.
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
        mesh.triangles.emplace_back(q[0], q[1], q[2]);
        mesh.triangles.emplace_back(q[0], q[2], q[3]);
    }
    if (inward) {
        for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
    }
    return mesh;
}

/// Icosphere of radius r centred at the origin: icosahedron split `levels` times, every vertex
/// on the sphere.
esf::Mesh make_sphere(double r, int levels) {
    const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Eigen::Vector3d> v = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                                      {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                                      {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
    for (auto& p : v) p.normalize();
    std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                      {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                      {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                      {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int level = 0; level < levels; ++level) {
        std::map<std::pair<int, int>, int> midpoints;
        const auto midpoint = [&](int a, int b) {
            const auto key = std::minmax(a, b);
            const auto it = midpoints.find(key);
            if (it != midpoints.end()) return it->second;
            v.push_back(
                (v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
            const int index = static_cast<int>(v.size()) - 1;
            midpoints.emplace(key, index);
            return index;
        };
        std::vector<Eigen::Vector3i> next;
        for (const auto& t : f) {
            const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]),
                      ca = midpoint(t[2], t[0]);
            next.emplace_back(t[0], ab, ca);
            next.emplace_back(ab, t[1], bc);
            next.emplace_back(ca, bc, t[2]);
            next.emplace_back(ab, bc, ca);
        }
        f = std::move(next);
    }
    esf::Mesh mesh;
    for (const auto& p : v) mesh.vertices.push_back((r * p).cast<float>());
    mesh.triangles = f;
    return mesh;
}

/// Smallest distance from the origin to the plane of a face: every surface point of the
/// tessellated sphere lies between this and the vertex radius.
double inner_radius(const esf::Mesh& mesh) {
    double inner = std::numeric_limits<double>::infinity();
    for (const auto& t : mesh.triangles) {
        const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(t[0])].cast<double>();
        const Eigen::Vector3d b = mesh.vertices[static_cast<std::size_t>(t[1])].cast<double>();
        const Eigen::Vector3d c = mesh.vertices[static_cast<std::size_t>(t[2])].cast<double>();
        const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
        inner = std::min(inner, std::abs(n.dot(a)));
    }
    return inner;
}

/// Ray t (camera depth z, rays (x, y, 1)) where the ray first meets the sphere (centre, r)
/// given in camera coordinates; nullopt when it misses.
std::optional<double> ray_sphere(const Eigen::Vector3d& d, const Eigen::Vector3d& centre,
                                 double r) {
    const double a = d.squaredNorm();
    const double b = d.dot(centre);
    const double disc = b * b - a * (centre.squaredNorm() - r * r);
    if (disc < 0.0) return std::nullopt;
    return (b - std::sqrt(disc)) / a;
}

esf::RenderOptions exact_options() {
    esf::RenderOptions options;
    options.noise = esf::SensorNoise::kNone;
    return options;
}

TEST(Camera, Presets) {
    const esf::CameraIntrinsics kinect = esf::CameraIntrinsics::kinect();
    EXPECT_EQ(kinect.width, 640);
    EXPECT_EQ(kinect.height, 480);
    EXPECT_EQ(kinect.fx, 525.0);
    EXPECT_EQ(kinect.fy, 525.0);
    EXPECT_EQ(kinect.cx, 319.5);
    EXPECT_EQ(kinect.cy, 239.5);
    const esf::CameraIntrinsics pcl = esf::CameraIntrinsics::pcl_renderer();
    EXPECT_EQ(pcl.width, 150);
    EXPECT_EQ(pcl.height, 150);
    // 57 degrees across 150 pixels: 75 / tan(28.5 deg) = 138.13.
    EXPECT_NEAR(pcl.fx, 138.13, 0.01);
    EXPECT_EQ(pcl.fx, pcl.fy);
    EXPECT_NEAR(2.0 * std::atan(75.0 / pcl.fx) * 180.0 / std::numbers::pi, 57.0, 1e-12);
}

TEST(Camera, Validation) {
    esf::CameraIntrinsics c;
    c.width = 0;
    EXPECT_EQ(error_of([&] { c.validate(); }),
              "camera size must be in [1, 16384] pixels a side, got 0x480");
    c = {};
    c.fy = -1;
    EXPECT_EQ(error_of([&] { c.validate(); }), "camera focal lengths must be positive and finite");
    c = {};
    c.cx = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(error_of([&] { c.validate(); }), "camera principal point must be finite");
}

TEST(RenderScene, BoxFaceOnIsAPlaneAtTheExactDistance) {
    // A 0.2 x 0.1 x 0.05 m box seen straight down from 1 m: its top face (z = 0.025) is at
    // depth 0.975 exactly; a pixel sees it iff its ray meets the face rectangle there.
    const esf::Mesh box = make_box(0.2, 0.1, 0.05);
    const esf::SceneObject object{&box, Eigen::Isometry3d::Identity()};
    const Eigen::Isometry3d camera_pose = esf::look_at({0, 0, 1}, {0, 0, 0});
    esf::SceneOptions options;
    const esf::PointCloud cloud = esf::render_scene({&object, 1}, camera_pose, options);
    ASSERT_EQ(cloud.width, 640u);
    ASSERT_EQ(cloud.height, 480u);
    ASSERT_EQ(cloud.points.size(), 640u * 480u);
    ASSERT_EQ(cloud.labels.size(), cloud.points.size());
    const esf::CameraIntrinsics& c = options.camera;
    const double depth = 0.975;
    std::size_t hits = 0;
    for (int v = 0; v < c.height; ++v) {
        for (int u = 0; u < c.width; ++u) {
            // Camera x = world x, camera y = -world y (image up = world +y).
            const double x = depth * (u - c.cx) / c.fx;
            const double y = depth * (v - c.cy) / c.fy;
            const double margin_x = std::abs(std::abs(x) - 0.1);
            const double margin_y = std::abs(std::abs(y) - 0.05);
            ASSERT_GT(std::min(margin_x, margin_y), 1e-5) << "pixel on the edge: pick other sizes";
            const bool inside = std::abs(x) < 0.1 && std::abs(y) < 0.05;
            const std::size_t i = static_cast<std::size_t>(v) * 640 + static_cast<std::size_t>(u);
            const Eigen::Vector3f& p = cloud.points[i];
            if (inside) {
                ++hits;
                ASSERT_TRUE(p.allFinite()) << u << "," << v;
                EXPECT_NEAR(p.z(), depth, 2e-7);
                EXPECT_NEAR(p.x(), x, 2e-7);
                EXPECT_NEAR(p.y(), y, 2e-7);
                EXPECT_EQ(cloud.labels[i], esf::kSceneLabelFirstObject);
            } else {
                EXPECT_TRUE(std::isnan(p.x()) && std::isnan(p.y()) && std::isnan(p.z()));
                EXPECT_EQ(cloud.labels[i], esf::kSceneLabelNone);
            }
        }
    }
    // 108 columns (|u - 319.5| < 53.85) x 54 rows (|v - 239.5| < 26.92).
    EXPECT_EQ(hits, 108u * 54u);
}

TEST(RenderViews, BoxPointsLieOnItsSurface) {
    // Every point, mapped back by the view pose, lies on one of the six faces.
    const esf::Mesh box = make_box(0.3, 0.2, 0.1, {1.0, -2.0, 0.5});
    const std::vector<esf::RenderedView> views = esf::render_views(box, exact_options());
    ASSERT_EQ(views.size(), 80u);
    for (const esf::RenderedView& view : views) {
        ASSERT_GT(view.points.size(), 1000u) << "view " << view.index;
        const Eigen::Affine3d to_model(view.pose.cast<double>().inverse());
        for (const auto& p : view.points) {
            const Eigen::Vector3d q = to_model * p.cast<double>() - Eigen::Vector3d(1.0, -2.0, 0.5);
            const double face =
                std::max({std::abs(q.x()) / 0.15, std::abs(q.y()) / 0.1, std::abs(q.z()) / 0.05});
            ASSERT_NEAR(face, 1.0, 2e-5) << "view " << view.index;
        }
    }
}

TEST(RenderViews, TessellatedSphereDepthsAreExact) {
    // Icosphere of radius 0.1 (5120 faces): a surface point lies between the inner radius
    // (closest face plane) and 0.1, so every depth lies between the ray's hits with those two
    // spheres. Rays that meet the inner sphere must hit; rays that miss the outer must not.
    const double r = 0.1;
    const esf::Mesh sphere = make_sphere(r, 4);
    const double inner = inner_radius(sphere);
    ASSERT_GT(inner, 0.0998);
    ASSERT_LT(inner, 0.1);
    esf::RenderOptions options = exact_options();
    options.level = 0;
    const esf::MeshRenderer renderer(sphere, options);
    // fill 0.5 of 480 px: d = r sqrt(1 + (2 * 525 / 240)^2).
    EXPECT_NEAR(renderer.camera_distance(), r * std::sqrt(1.0 + 4.375 * 4.375), 1e-5);
    EXPECT_NEAR(renderer.radius(), r, 1e-5);

    const esf::CameraIntrinsics& c = options.camera;
    for (std::size_t i = 0; i < renderer.view_count(); ++i) {
        const esf::RenderedView view = renderer.render_view(i);
        const Eigen::Vector3d centre =
            (view.pose.cast<double>() * Eigen::Vector4d(0, 0, 0, 1)).head<3>();
        EXPECT_NEAR(centre.z(), renderer.camera_distance(), 1e-6);
        EXPECT_NEAR(centre.head<2>().norm(), 0.0, 1e-6);
        // Map each point to its pixel; check it against both spheres.
        std::vector<char> hit(static_cast<std::size_t>(c.width * c.height), 0);
        int u_min = c.width, u_max = -1;
        for (const auto& p : view.points) {
            const double u = c.fx * p.x() / p.z() + c.cx;
            const double v = c.fy * p.y() / p.z() + c.cy;
            const int pu = static_cast<int>(std::lround(u));
            const int pv = static_cast<int>(std::lround(v));
            ASSERT_NEAR(u, pu, 1e-3);
            ASSERT_NEAR(v, pv, 1e-3);
            hit[static_cast<std::size_t>(pv * c.width + pu)] = 1;
            u_min = std::min(u_min, pu);
            u_max = std::max(u_max, pu);
            const Eigen::Vector3d d((pu - c.cx) / c.fx, (pv - c.cy) / c.fy, 1.0);
            const auto outer_t = ray_sphere(d, centre, r);
            ASSERT_TRUE(outer_t.has_value());
            EXPECT_GE(p.z(), *outer_t - 1e-6);
            if (const auto inner_t = ray_sphere(d, centre, inner)) {
                EXPECT_LE(p.z(), *inner_t + 1e-6);
            }
            EXPECT_GE((Eigen::Vector3d(p.cast<double>()) - centre).norm(), inner - 1e-6);
            EXPECT_LE((Eigen::Vector3d(p.cast<double>()) - centre).norm(), r + 1e-6);
        }
        std::size_t must_hit = 0;
        for (int v = 0; v < c.height; ++v) {
            for (int u = 0; u < c.width; ++u) {
                const Eigen::Vector3d d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
                if (ray_sphere(d, centre, inner - 1e-6)) {
                    ++must_hit;
                    EXPECT_TRUE(hit[static_cast<std::size_t>(v * c.width + u)]) << u << "," << v;
                }
            }
        }
        EXPECT_GT(must_hit, 40000u);
        // The sphere spans fill_fraction * 480 = 240 pixels.
        EXPECT_NEAR(u_max - u_min + 1, 240, 2);
    }
}

TEST(RenderViews, ScaleAndTargetExtent) {
    // A 45 mm "KIT-like" box (middle side 45) rescaled to a longest side of 0.3 m.
    const esf::Mesh box = make_box(90, 45, 30);
    esf::RenderOptions options = exact_options();
    options.level = 0;
    options.target_extent = 0.3;
    const esf::MeshRenderer renderer(box, options);
    EXPECT_DOUBLE_EQ(renderer.scale(), 0.3 / 90.0);
    const double radius = 0.5 * std::sqrt(0.3 * 0.3 + 0.15 * 0.15 + 0.1 * 0.1);
    EXPECT_NEAR(renderer.radius(), radius, 1e-5);
    const esf::RenderedView view = renderer.render_view(5);
    // The pose maps file coordinates: its 3x3 block is scale * rotation.
    const Eigen::Matrix3d block = view.pose.topLeftCorner<3, 3>().cast<double>();
    EXPECT_NEAR((block.transpose() * block -
                 renderer.scale() * renderer.scale() * Eigen::Matrix3d::Identity())
                    .norm(),
                0.0, 1e-9);
    for (const auto& p : view.points) {
        const Eigen::Vector3d q =
            (view.pose.cast<double>().inverse() * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0))
                .head<3>();
        ASSERT_NEAR(std::max({std::abs(q.x()) / 45, std::abs(q.y()) / 22.5, std::abs(q.z()) / 15}),
                    1.0, 1e-4);
    }
    // The same through `scale`.
    esf::RenderOptions scaled = options;
    scaled.target_extent.reset();
    scaled.scale = 0.3 / 90.0;
    const esf::RenderedView same = esf::MeshRenderer(box, scaled).render_view(5);
    ASSERT_EQ(same.points.size(), view.points.size());
    for (std::size_t i = 0; i < view.points.size(); ++i)
        EXPECT_LT((same.points[i] - view.points[i]).norm(), 1e-6f);

    // A fixed camera distance.
    esf::RenderOptions fixed = options;
    fixed.distance = 1.0;
    EXPECT_EQ(esf::MeshRenderer(box, fixed).camera_distance(), 1.0);
}

TEST(RenderViews, BothFacesAreHit) {
    // Inward-facing triangles render exactly like outward ones, and an open single triangle is
    // seen from behind.
    esf::RenderOptions options = exact_options();
    options.level = 0;
    const auto out = esf::render_views(make_box(0.1, 0.2, 0.3), options);
    const auto in = esf::render_views(make_box(0.1, 0.2, 0.3, {0, 0, 0}, true), options);
    for (std::size_t i = 0; i < out.size(); ++i) {
        ASSERT_EQ(out[i].points.size(), in[i].points.size());
        for (std::size_t k = 0; k < out[i].points.size(); ++k)
            ASSERT_LT((out[i].points[k] - in[i].points[k]).norm(), 1e-6f);
    }
    esf::Mesh triangle;
    triangle.vertices = {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}};
    triangle.triangles = {{0, 1, 2}};
    const esf::MeshRenderer renderer(triangle, options);
    const Eigen::Isometry3d above = esf::look_at({0.03, 0.03, 0.5}, {0.03, 0.03, 0});
    const Eigen::Isometry3d below = esf::look_at({0.03, 0.03, -0.5}, {0.03, 0.03, 0});
    const std::size_t front = renderer.render_pose(above, 0).size();
    const std::size_t back = renderer.render_pose(below, 0).size();
    EXPECT_GT(front, 1000u);
    EXPECT_NEAR(static_cast<double>(back), static_cast<double>(front),
                0.02 * static_cast<double>(front));
}

TEST(RenderViews, RegionOfInterestLosesNothing) {
    // render_pose casts only the rays that can meet the bounding sphere; render_scene casts the
    // whole image. Off-centre poses, same points in the same order.
    const esf::Mesh ellipsoid = [] {
        esf::Mesh m = make_sphere(1.0, 3);
        for (auto& v : m.vertices) v = v.cwiseProduct(Eigen::Vector3f(0.12f, 0.05f, 0.08f));
        return m;
    }();
    esf::RenderOptions options = exact_options();
    const esf::MeshRenderer renderer(ellipsoid, options);
    ASSERT_EQ(renderer.centre(), Eigen::Vector3d::Zero());
    for (const Eigen::Vector3d& target : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.15, 0.1, 0),
                                          Eigen::Vector3d(-0.2, 0.05, 0.1)}) {
        const Eigen::Isometry3d pose = esf::look_at({0.3, -0.4, 0.35}, target);
        const esf::Points roi = renderer.render_pose(pose, 0);
        const esf::SceneObject object{&ellipsoid, Eigen::Isometry3d::Identity()};
        esf::SceneOptions scene_options;
        const esf::Points full =
            esf::drop_non_finite(esf::render_scene({&object, 1}, pose, scene_options).points)
                .points;
        ASSERT_GT(roi.size(), 1000u);
        ASSERT_EQ(roi.size(), full.size());
        for (std::size_t i = 0; i < roi.size(); ++i) ASSERT_LT((roi[i] - full[i]).norm(), 1e-6f);
    }
}

TEST(RenderViews, DeterministicWhateverTheThreadCount) {
    const esf::Mesh sphere = make_sphere(0.05, 3);
    esf::RenderOptions options;  // Kinect noise on
    options.seed = 42;
    options.threads = 1;
    const auto one = esf::render_views(sphere, options);
    options.threads = 3;
    const auto three = esf::render_views(sphere, options);
    const auto again = esf::render_views(sphere, options);
    options.seed = 43;
    const auto other = esf::render_views(sphere, options);
    ASSERT_EQ(one.size(), three.size());
    std::size_t differing = 0;
    for (std::size_t i = 0; i < one.size(); ++i) {
        EXPECT_EQ(one[i].index, static_cast<int>(i));
        EXPECT_EQ(one[i].pose, three[i].pose);
        ASSERT_EQ(one[i].points, three[i].points);
        ASSERT_EQ(three[i].points, again[i].points);
        differing += one[i].points != other[i].points ? 1 : 0;
    }
    EXPECT_EQ(differing, one.size());
}

TEST(RenderViews, KinectDepthsAreQuantisedDisparities) {
    // Every depth is fx * 0.075 / (k / 8) for an integer k. The noise (sigma 1.2 mm at 0.36 m,
    // more at grazing angles) keeps points near the surface, unbiased.
    const esf::Mesh sphere = make_sphere(0.08, 3);
    esf::RenderOptions options;
    options.level = 0;
    options.seed = 7;
    const esf::MeshRenderer renderer(sphere, options);
    const std::size_t exact =
        esf::MeshRenderer(sphere, exact_options()).render_view(0).points.size();
    for (std::size_t i = 0; i < renderer.view_count(); ++i) {
        const esf::RenderedView view = renderer.render_view(i);
        // Grazing-angle drops remove a rim of the disc, not more.
        ASSERT_LT(view.points.size(), exact);
        ASSERT_GT(view.points.size(), exact * 8 / 10);
        const Eigen::Vector3d centre =
            (view.pose.cast<double>() * Eigen::Vector4d(0, 0, 0, 1)).head<3>();
        std::size_t near = 0;
        double sum = 0.0;
        for (const auto& p : view.points) {
            const double k = 8.0 * 525.0 * 0.075 / p.z();
            ASSERT_NEAR(k, std::round(k), 1e-3);
            const double radius = (p.cast<double>() - centre).norm();
            ASSERT_NEAR(radius, 0.08, 0.15);  // sigma reaches ~5 cm at 85 degrees
            near += std::abs(radius - 0.08) < 0.004 ? 1 : 0;
            sum += radius;
        }
        EXPECT_GT(near, view.points.size() * 97 / 100);
        EXPECT_NEAR(sum / static_cast<double>(view.points.size()), 0.08, 0.0005);
    }
}

TEST(RenderScene, TableLabelsAndGrazingDrops) {
    // Two boxes on a table (their bottoms at z = 0), seen from the side and above.
    const esf::Mesh tall = make_box(0.1, 0.1, 0.3, {0, 0, 0.15});
    const esf::Mesh flat = make_box(0.2, 0.1, 0.05, {0, 0, 0.025});
    Eigen::Isometry3d left = Eigen::Isometry3d::Identity();
    left.translation() = Eigen::Vector3d(0, -0.2, 0);
    Eigen::Isometry3d right = Eigen::Isometry3d::Identity();
    right.translation() = Eigen::Vector3d(0, 0.2, 0);
    const std::vector<esf::SceneObject> objects = {{&tall, left}, {&flat, right}};
    const Eigen::Isometry3d camera = esf::look_at({1.0, 0, 0.6}, {0, 0, 0.05});
    esf::SceneOptions options;
    options.table_plane = true;
    options.table_half_size = 0.6;
    const esf::PointCloud cloud = esf::render_scene(objects, camera, options);
    const esf::CameraIntrinsics& c = options.camera;
    const auto pixel_of = [&](const Eigen::Vector3d& world) {
        const Eigen::Vector3d p = camera * world;
        const auto u = static_cast<std::size_t>(std::lround(c.fx * p.x() / p.z() + c.cx));
        const auto v = static_cast<std::size_t>(std::lround(c.fy * p.y() / p.z() + c.cy));
        return v * static_cast<std::size_t>(c.width) + u;
    };
    EXPECT_EQ(cloud.labels[pixel_of({0.05, -0.2, 0.15})], esf::kSceneLabelFirstObject + 0);
    EXPECT_EQ(cloud.labels[pixel_of({0.1, 0.2, 0.025})], esf::kSceneLabelFirstObject + 1);
    const std::size_t table = pixel_of({0.3, 0.0, 0.0});
    EXPECT_EQ(cloud.labels[table], esf::kSceneLabelTable);
    // Beyond the table's edge there is nothing; the top image rows look over it.
    EXPECT_EQ(cloud.labels[5], esf::kSceneLabelNone);
    EXPECT_TRUE(std::isnan(cloud.points[5].z()));
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
        if (cloud.labels[i] == esf::kSceneLabelTable) {
            const Eigen::Vector3d world = camera.inverse() * cloud.points[i].cast<double>();
            ASSERT_NEAR(world.z(), 0.0, 1e-5);
            ASSERT_LE(std::max(std::abs(world.x()), std::abs(world.y())), 0.6 + 1e-5);
        }
        ASSERT_EQ(cloud.labels[i] == esf::kSceneLabelNone, std::isnan(cloud.points[i].z()));
    }

    // A camera 5 cm above an infinite table looking 16.7 degrees down: with the Kinect model,
    // pixels seeing the table at more than 85 degrees from its normal (rows 83-130) are
    // dropped, those under 65 degrees (rows 317-479) kept.
    const Eigen::Isometry3d low = esf::look_at({0, 0, 0.05}, {1, 0, -0.25});
    esf::SceneOptions noisy;
    noisy.table_plane = true;
    noisy.noise = esf::SensorNoise::kKinect;
    noisy.seed = 3;
    const esf::PointCloud grazing = esf::render_scene({}, low, noisy);
    std::size_t checked_drop = 0, checked_keep = 0;
    for (int v = 0; v < c.height; ++v) {
        for (int u = 0; u < c.width; ++u) {
            const Eigen::Vector3d d = low.linear().transpose() *
                                      Eigen::Vector3d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
            if (d.z() >= 0.0) continue;  // above the horizon
            const double theta = std::acos(-d.z() / d.norm()) * 180.0 / std::numbers::pi;
            const auto i = static_cast<std::size_t>(v * c.width + u);
            if (theta > 85.01) {
                EXPECT_TRUE(std::isnan(grazing.points[i].z()));
                ++checked_drop;
            } else if (theta < 64.99) {
                EXPECT_FALSE(std::isnan(grazing.points[i].z()));
                ++checked_keep;
            }
        }
    }
    EXPECT_GT(checked_drop, 10000u);
    EXPECT_GT(checked_keep, 10000u);

    // max_depth drops far returns.
    esf::SceneOptions near = noisy;
    near.noise = esf::SensorNoise::kNone;
    near.max_depth = 1.0;
    const esf::PointCloud clipped = esf::render_scene({}, low, near);
    for (const auto& p : clipped.points) {
        if (!std::isnan(p.z())) {
            ASSERT_LE(p.z(), 1.0f);
        }
    }
}

TEST(RenderScene, ThreadCountDoesNotMatter) {
    const esf::Mesh sphere = make_sphere(0.1, 3);
    const esf::SceneObject object{&sphere, Eigen::Isometry3d::Identity()};
    esf::SceneOptions options;
    options.table_plane = true;
    options.noise = esf::SensorNoise::kKinect;
    options.seed = 11;
    options.threads = 1;
    const Eigen::Isometry3d camera = esf::look_at({0.6, 0.3, 0.5}, {0, 0, 0});
    const esf::PointCloud one = esf::render_scene({&object, 1}, camera, options);
    options.threads = 4;
    const esf::PointCloud four = esf::render_scene({&object, 1}, camera, options);
    ASSERT_EQ(one.labels, four.labels);
    for (std::size_t i = 0; i < one.points.size(); ++i) {
        if (std::isnan(one.points[i].z())) {
            ASSERT_TRUE(std::isnan(four.points[i].z()));
        } else {
            ASSERT_EQ(one.points[i], four.points[i]);
        }
    }
}

TEST(Render, InputsEmbreeCannotTakeAreRefusedFirst) {
    // Embree aborts on ray origins or directions beyond about 1.8e18; these would reach it.
    const esf::Mesh box = make_box(0.1, 0.1, 0.1);
    esf::RenderOptions options;
    options.distance = 1e20;
    EXPECT_EQ(error_of([&] { esf::render_views(box, options); }),
              "camera distance must be at most 1e6 m, got 100000000000000000000.000000 m");
    options = {};
    options.distance = 0.6;
    options.max_distance = 1e7;
    EXPECT_EQ(error_of([&] { esf::render_views(box, options); }),
              "largest camera distance must be at most 1e6 m, got 10000000.000000 m");
    options = {};
    options.camera.fx = options.camera.fy = 1e30;  // the automatic distance: about 1e29 m
    EXPECT_CONTAINS(error_of([&] { esf::render_views(box, options); }),
                    "camera distance must be at most 1e6 m, got ");
    options = {};
    options.camera.fx = 1e-30;  // rays 1e32 times wider than deep
    EXPECT_CONTAINS(error_of([&] { esf::render_views(box, options); }),
                    "renderer: the camera's principal point lies too far outside the image");
    options = {};
    options.camera.cy = -1e300;
    EXPECT_CONTAINS(error_of([&] { esf::render_views(box, options); }), "too far outside");

    // Just inside the limits, it renders.
    options = {};
    options.distance = 1e6;
    options.level = 0;
    EXPECT_EQ(esf::render_views(box, options).size(), 20u);

    const esf::MeshRenderer renderer(box, esf::RenderOptions{});
    Eigen::Isometry3d far_away = Eigen::Isometry3d::Identity();
    far_away.translation() = Eigen::Vector3d(0, 0, 1e20);
    EXPECT_CONTAINS(error_of([&] { renderer.render_pose(far_away, 0); }),
                    "render_pose: the camera's distance from the model must be at most 1e6 m");
    const esf::SceneObject object{&box, Eigen::Isometry3d::Identity()};
    EXPECT_CONTAINS(error_of([&] {
                        esf::render_scene({&object, 1}, far_away, {});
                    }),
                    "render_scene: the camera's distance from the world origin must be at most");
}

TEST(Render, ErrorsSayWhatIsWrong) {
    const esf::Mesh box = make_box(0.1, 0.1, 0.1);
    esf::RenderOptions options;
    options.level = 7;
    EXPECT_EQ(error_of([&] { esf::render_views(box, options); }),
              "view sphere level must be in [0, 6], got 7");
    options = {};
    options.fill_fraction = 0.0;
    EXPECT_EQ(error_of([&] { esf::render_views(box, options); }),
              "fill fraction must be positive and finite, got 0.000000");
    options = {};
    options.scale = -1.0;
    EXPECT_EQ(error_of([&] { esf::render_views(box, options); }),
              "model scale must be positive and finite, got -1.000000");
    options = {};
    options.target_extent = 0.0;
    EXPECT_EQ(error_of([&] { esf::render_views(box, options); }),
              "target extent must be positive and finite, got 0.000000");
    options = {};
    options.distance = 0.05;
    EXPECT_EQ(
        error_of([&] {
            esf::render_views(box, options);
        }).rfind("camera distance must be finite and exceed the model's bounding sphere radius", 0),
        0u);
    options = {};
    options.threads = -2;
    EXPECT_THROW(esf::render_views(box, options), std::invalid_argument);
    options = {};
    EXPECT_EQ(error_of([&] { esf::render_views(esf::Mesh{}, options); }),
              "render: mesh has no triangle");
    esf::Mesh point = box;
    for (auto& v : point.vertices) v = Eigen::Vector3f(1, 2, 3);
    EXPECT_EQ(error_of([&] { esf::render_views(point, options); }),
              "mesh has zero extent (all vertices equal)");
    const esf::MeshRenderer renderer(box, options);
    EXPECT_EQ(error_of([&] { renderer.render_view(80); }), "view index 80 out of range (80 views)");

    const esf::SceneObject null_object{nullptr, Eigen::Isometry3d::Identity()};
    EXPECT_EQ(error_of([&] {
                  esf::render_scene({&null_object, 1}, Eigen::Isometry3d::Identity(), {});
              }),
              "scene object 0: no mesh");
    esf::Mesh bad = box;
    bad.triangles[3] = Eigen::Vector3i(0, 1, 8);
    const esf::SceneObject bad_object{&bad, Eigen::Isometry3d::Identity()};
    EXPECT_EQ(error_of([&] {
                  esf::render_scene({&bad_object, 1}, Eigen::Isometry3d::Identity(), {});
              }),
              "scene object 0: triangle 3 has a vertex index outside [0, 8)");
}

}  // namespace

namespace {

TEST(MeshRenderer, ElevationBandKeepsTheCamerasAboveTheModel) {
    const esf::Mesh box = make_box(0.1, 0.08, 0.2);
    esf::RenderOptions options;
    options.distance = 0.8;
    options.min_elevation = 0.0;
    const esf::MeshRenderer renderer(box, options);
    const auto sphere = esf::view_sphere(options.level);
    std::size_t upper = 0;
    for (const auto& d : sphere) upper += d.z() >= 0.0;
    ASSERT_EQ(renderer.view_count(), upper);
    EXPECT_LT(upper, sphere.size());
    int previous = -1;
    for (std::size_t i = 0; i < renderer.view_count(); ++i) {
        const int index = renderer.view_index(i);
        EXPECT_GT(index, previous);  // view sphere order
        previous = index;
        EXPECT_GE(sphere[static_cast<std::size_t>(index)].z(), 0.0) << index;
    }
    const esf::RenderedView view = renderer.render_view(3);
    EXPECT_EQ(view.index, renderer.view_index(3));
    EXPECT_EQ(error_of([&] { renderer.view_index(upper); }), "view index " + std::to_string(upper) +
                                                                 " out of range (" +
                                                                 std::to_string(upper) + " views)");

    options.min_elevation = 30.0;
    options.max_elevation = 10.0;
    EXPECT_EQ(error_of([&] { esf::MeshRenderer(box, options); }),
              "camera elevations must satisfy -90 <= min <= max <= 90 degrees, got [30.000000, "
              "10.000000]");
    options.min_elevation = options.max_elevation = 90.0;
    EXPECT_EQ(error_of([&] { esf::MeshRenderer(box, options); }),
              "no camera of view sphere level 1 has an elevation in [90.000000, 90.000000] "
              "degrees");
}

TEST(MeshRenderer, CameraDistancesAreDrawnFromTheRange) {
    const esf::Mesh box = make_box(0.1, 0.08, 0.2);
    esf::RenderOptions options;
    options.distance = 0.6;
    options.max_distance = 1.2;
    options.seed = 5;
    const esf::MeshRenderer renderer(box, options);
    double lo = 10.0, hi = 0.0;
    for (std::size_t i = 0; i < renderer.view_count(); ++i) {
        const esf::RenderedView view = renderer.render_view(i);
        // The model's centre (the origin of the box) lies this far from the camera.
        const double d = view.pose.col(3).head<3>().cast<double>().norm();
        EXPECT_GE(d, 0.6 - 1e-5);
        EXPECT_LE(d, 1.2 + 1e-5);
        lo = std::min(lo, d);
        hi = std::max(hi, d);
        EXPECT_EQ(renderer.render_view(i).points, view.points);  // the same draw every time
    }
    EXPECT_LT(lo, 0.75);
    EXPECT_GT(hi, 1.05);
    // At or below the distance, every view is seen from the distance.
    options.max_distance = 0.5;
    const esf::MeshRenderer fixed(box, options);
    const Eigen::Matrix4f pose = fixed.render_view(0).pose;
    EXPECT_NEAR(pose.col(3).head<3>().cast<double>().norm(), 0.6, 1e-5);
    options.max_distance = -1.0;
    EXPECT_EQ(error_of([&] { esf::MeshRenderer(box, options); }),
              "largest camera distance must be positive and finite, got -1.000000");
}

}  // namespace
