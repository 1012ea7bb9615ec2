// Hypothesis verification against hand-made geometry: surface samples on a box's faces with
// outward normals, a pose recovered from a rendered view, the right shape scoring above a wrong
// one, and free space seen through a wrong hypothesis.

#include "esf/recognition/pose_verification.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "esf/render/render.hpp"
#include "esf/render/view_sphere.hpp"
#include "support/test_meshes.hpp"

namespace {

// Model -> camera: the model stands on z = 0 of a table seen 45 degrees from above, 0.8 m away.
Eigen::Isometry3d standing_pose(double yaw_deg) {
    const Eigen::Isometry3d world_to_camera =
        esf::look_at(Eigen::Vector3d(0.0, -0.57, 0.57), Eigen::Vector3d(0.0, 0.0, 0.08));
    Eigen::Isometry3d model_to_world = Eigen::Isometry3d::Identity();
    model_to_world.rotate(
        Eigen::AngleAxisd(yaw_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()));
    return world_to_camera * model_to_world;
}

esf::Points render(const esf::Mesh& mesh, const Eigen::Isometry3d& pose) {
    esf::RenderOptions options;
    options.noise = esf::SensorNoise::kNone;
    options.distance = 0.8;
    return esf::MeshRenderer(mesh, options).render_pose(pose, 0);
}

// The matched view's rotation, 10 degrees off the truth, from a camera looking straight at the
// model.
Eigen::Matrix4d view_ten_degrees_off(const Eigen::Isometry3d& truth) {
    Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
    view.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(10.0 * std::numbers::pi / 180.0, Eigen::Vector3d(1, 1, 0).normalized())
            .toRotationMatrix() *
        truth.linear();
    return view;
}

double rotation_error_deg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    return Eigen::AngleAxisd(a.transpose() * b).angle() * 180.0 / std::numbers::pi;
}

TEST(ModelSurface, SamplesLieOnTheFacesWithOutwardNormals) {
    for (const bool clockwise : {false, true}) {
        const esf::ModelSurface s = esf::sample_model_surface(
            esf::test::standing_box(0.2, 0.1, 0.3, clockwise), 2.0, 4000, 5);
        ASSERT_EQ(s.points.size(), 4000u);
        EXPECT_NEAR(s.diameter, 2.0 * 2.0 * std::sqrt(0.01 + 0.0025 + 0.0225), 1e-6);
        std::size_t top = 0;
        for (std::size_t i = 0; i < s.points.size(); ++i) {
            const Eigen::Vector3d p = s.points[i].cast<double>() / 2.0;  // file units
            const Eigen::Vector3d d =
                (p - Eigen::Vector3d(0, 0, 0.15)).cwiseAbs() - Eigen::Vector3d(0.1, 0.05, 0.15);
            EXPECT_NEAR(d.maxCoeff(), 0.0, 1e-6) << "not on a face";
            EXPECT_GT(s.normals[i].cast<double>().dot(p - Eigen::Vector3d(0, 0, 0.15)), 0.0);
            top += p.z() > 0.3 - 1e-6;
        }
        // The top face holds 0.02 of the 0.22 m^2 (file units).
        EXPECT_NEAR(static_cast<double>(top) / 4000.0, 0.02 / 0.22, 0.01);
    }
    EXPECT_THROW(esf::sample_model_surface(esf::test::standing_box(0.1, 0.1, 0.1), 0.0, 10, 0),
                 std::invalid_argument);
    EXPECT_THROW(esf::sample_model_surface(esf::test::standing_box(0.1, 0.1, 0.1), 1.0, 0, 0),
                 std::invalid_argument);
}

TEST(FitModel, RecoversThePoseFromAPerturbedView) {
    const esf::Mesh box = esf::test::standing_box(0.16, 0.08, 0.22);
    const Eigen::Isometry3d truth = standing_pose(25.0);
    const esf::Points seen = render(box, truth);
    ASSERT_GT(seen.size(), 2000u);
    const Eigen::Matrix4d view = view_ten_degrees_off(truth);
    const esf::ModelSurface surface = esf::sample_model_surface(box, 1.0, 3000, 1);
    const esf::PoseFit fit = esf::fit_model(surface, view, {seen, nullptr}, {});
    EXPECT_LT(rotation_error_deg(fit.model_to_camera.topLeftCorner<3, 3>(), truth.linear()), 2.0);
    EXPECT_LT((fit.model_to_camera.topRightCorner<3, 1>() - truth.translation()).norm(), 0.004);
    EXPECT_GT(fit.fit.inliers, 0.95);
    EXPECT_GT(fit.fit.support, 0.9);
    EXPECT_LT(fit.fit.violations, 0.05);
    EXPECT_LT(fit.fit.rms_mm, 2.0);
    EXPECT_TRUE(fit.verified);
    EXPECT_EQ(fit.scale, 1.0);
}

TEST(FitModel, TwoWayPairsKeepAFreeSizeWhereTheObjectIsCut) {
    // The box seen with its lower 40 % hidden (a nearer object in front of it), its size free:
    // model samples below the cut pull the model in and shrink it; paired both ways, the
    // object's points hold it nearer its size.
    const esf::Mesh box = esf::test::standing_box(0.16, 0.08, 0.22);
    const Eigen::Isometry3d truth = standing_pose(25.0);
    const esf::Points whole = render(box, truth);
    esf::Points seen;
    for (const Eigen::Vector3f& p : whole)
        if ((truth.inverse() * p.cast<double>()).z() > 0.4 * 0.22) seen.push_back(p);
    ASSERT_GT(seen.size(), 1000u);
    const Eigen::Matrix4d view = view_ten_degrees_off(truth);
    const esf::ModelSurface surface = esf::sample_model_surface(box, 1.0, 3000, 1);
    esf::VerificationOptions one_way;
    esf::VerificationOptions two_way;
    two_way.two_way = true;
    const esf::PoseFit a = esf::fit_model(surface, view, {seen, nullptr}, one_way, true);
    const esf::PoseFit b = esf::fit_model(surface, view, {seen, nullptr}, two_way, true);
    // One way shrinks the box by about an eighth, two ways by about a twentieth (3,000
    // samples of a box's faces): the model explains more of what was seen.
    EXPECT_LT(a.scale, 0.9);
    EXPECT_LT(std::abs(b.scale - 1.0), 0.5 * std::abs(a.scale - 1.0));
    EXPECT_GT(b.fit.inliers, a.fit.inliers);
    EXPECT_LT(rotation_error_deg(b.model_to_camera.topLeftCorner<3, 3>() / b.scale, truth.linear()),
              3.0);
}

TEST(FitModel, ACameraPoseStartKeepsItsRotation) {
    // A box well off the optical axis (about 18 degrees), and a start 5 degrees from its pose in
    // this camera: an earlier fit of the same object. Kept as it is, one ICP step lands near the
    // truth; taken as a training view's (turned towards the object) it starts 20 degrees away.
    const esf::Mesh box = esf::test::standing_box(0.16, 0.08, 0.22);
    Eigen::Isometry3d truth = standing_pose(25.0);
    truth.pretranslate(Eigen::Vector3d(0.25, 0.0, 0.0));
    const esf::Points seen = render(box, truth);
    ASSERT_GT(seen.size(), 1000u);
    Eigen::Matrix4d start = truth.matrix();
    start.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(5.0 * std::numbers::pi / 180.0, Eigen::Vector3d(1, 0, 1).normalized())
            .toRotationMatrix() *
        truth.linear();
    const esf::ModelSurface surface = esf::sample_model_surface(box, 1.0, 3000, 1);
    const esf::PreparedModel model(surface);
    const esf::PreparedObservation observation({seen, nullptr}, esf::CameraIntrinsics::kinect());
    esf::VerificationOptions one_step;
    one_step.iterations = 1;
    const auto error_deg = [&](const esf::PoseFit& f) {
        return rotation_error_deg(f.model_to_camera.topLeftCorner<3, 3>(), truth.linear());
    };
    const esf::PoseFit kept =
        esf::fit_model(model, start, observation, one_step, false, esf::FitStart::kCameraPose);
    const esf::PoseFit turned =
        esf::fit_model(model, start, observation, one_step, false, esf::FitStart::kTrainingView);
    EXPECT_LT(error_deg(kept), 5.0);
    EXPECT_GT(error_deg(turned), 2.0 * error_deg(kept)) << error_deg(kept);
    const esf::PoseFit full =
        esf::fit_model(model, start, observation, {}, false, esf::FitStart::kCameraPose);
    EXPECT_LT(error_deg(full), 2.0);
    EXPECT_LT((full.model_to_camera.topRightCorner<3, 1>() - truth.translation()).norm(), 0.004);
    EXPECT_TRUE(full.verified);
}

TEST(FitModel, APreparedModelFitsAsItsSurfaceDoesAndAThinnedCloudStillSupportsIt) {
    const esf::Mesh box = esf::test::standing_box(0.16, 0.08, 0.22);
    const Eigen::Isometry3d truth = standing_pose(25.0);
    const esf::Points seen = render(box, truth);
    Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
    view.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()).toRotationMatrix() * truth.linear();
    esf::ModelSurface surface = esf::sample_model_surface(box, 1.0, 3000, 1);
    const esf::PoseFit plain = esf::fit_model(surface, view, {seen, nullptr}, {});
    const esf::PreparedModel model(surface);
    const esf::VerificationOptions options;
    const esf::PreparedObservation observation({seen, nullptr}, options.camera);
    const esf::PoseFit prepared = esf::fit_model(model, view, observation, options);
    EXPECT_EQ(prepared.model_to_camera, plain.model_to_camera);
    EXPECT_EQ(prepared.fit.inliers, plain.fit.inliers);
    EXPECT_EQ(prepared.fit.support, plain.fit.support);
    // Every fifth point: a thinned cloud still supports the whole visible surface.
    esf::Points thinned;
    for (std::size_t i = 0; i < seen.size(); i += 5) thinned.push_back(seen[i]);
    const esf::PoseFit sparse = esf::fit_model(
        model, view, esf::PreparedObservation({thinned, nullptr}, options.camera), options);
    EXPECT_GT(sparse.fit.support, 0.9);
    EXPECT_GT(sparse.fit.inliers, 0.95);
    surface.normals.pop_back();
    EXPECT_THROW(esf::PreparedModel{surface}, std::invalid_argument);
    EXPECT_THROW(esf::PreparedModel{esf::ModelSurface{}}, std::invalid_argument);
}

// A can seen from 45 degrees, and a box of its size: both started from the can's true rotation.
struct CanAndBox {
    esf::Mesh can = esf::test::standing_cylinder(0.04, 0.12, 64);
    esf::Mesh box = esf::test::standing_box(0.08, 0.08, 0.12);
    esf::Points seen = render(can, standing_pose(0.0));
    Eigen::Matrix4d view = start(standing_pose(0.0));

    static Eigen::Matrix4d start(const Eigen::Isometry3d& truth) {
        Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
        m.topLeftCorner<3, 3>() = truth.linear();
        return m;
    }
};

TEST(FitModel, TheRightShapeScoresAboveABoxOfItsSize) {
    const auto [can, box, seen, view] = CanAndBox{};
    for (const bool free_scale : {false, true}) {
        const esf::PoseFit as_can = esf::fit_model(esf::sample_model_surface(can, 1.0, 3000, 1),
                                                   view, {seen, nullptr}, {}, free_scale);
        const esf::PoseFit as_box = esf::fit_model(esf::sample_model_surface(box, 1.0, 3000, 1),
                                                   view, {seen, nullptr}, {}, free_scale);
        EXPECT_GT(as_can.fit.score(), as_box.fit.score() + 0.1) << free_scale;
        EXPECT_TRUE(as_can.verified);
        EXPECT_GE(as_box.scale, 0.8);
        EXPECT_LE(as_box.scale, 1.25);
    }
}

TEST(FitModel, AHypothesisThatMustBeatAnotherStopsOnlyWhenItCannot) {
    const auto [can, box, seen, view] = CanAndBox{};
    const esf::VerificationOptions options;
    const esf::PreparedObservation observation({seen, nullptr}, options.camera);
    for (const esf::Mesh* mesh : {&can, &box}) {
        const esf::PreparedModel model(esf::sample_model_surface(*mesh, 1.0, 3000, 1));
        const esf::PoseFit whole = esf::fit_model(model, view, observation, options);
        ASSERT_FALSE(whole.abandoned);
        const double score = whole.fit.score();
        // A bar it clears, or just meets from below: scored whole, the same numbers.
        for (const double bar : {-1.0, score - 0.05, score - 1e-6}) {
            const esf::PoseFit f = esf::fit_model(model, view, observation, options, false,
                                                  esf::FitStart::kTrainingView, bar);
            EXPECT_FALSE(f.abandoned) << bar;
            EXPECT_EQ(f.fit.score(), score) << bar;
            EXPECT_EQ(f.model_to_camera, whole.model_to_camera) << bar;
        }
        // A bar above what it scores: dropped, and flagged as such.
        for (const double bar : {score + 0.05, 1.5}) {
            const esf::PoseFit f = esf::fit_model(model, view, observation, options, false,
                                                  esf::FitStart::kTrainingView, bar);
            EXPECT_TRUE(f.abandoned) << bar;
            EXPECT_FALSE(f.verified) << bar;
        }
    }
}

TEST(FitModel, AFrameShowsTheTableThroughAWrongHypothesis) {
    // A can on a table; a box as wide as the can puts its corners where the table is seen.
    const esf::Mesh can = esf::test::standing_cylinder(0.04, 0.12, 64);
    const Eigen::Isometry3d world_to_camera =
        esf::look_at(Eigen::Vector3d(0.0, -0.57, 0.57), Eigen::Vector3d(0.0, 0.0, 0.06));
    const esf::SceneObject object{&can, Eigen::Isometry3d::Identity()};
    esf::SceneOptions options;
    options.table_plane = true;
    const esf::PointCloud frame = esf::render_scene({&object, 1}, world_to_camera, options);
    esf::Points seen;
    for (std::size_t i = 0; i < frame.points.size(); ++i)
        if (frame.labels[i] == esf::kSceneLabelFirstObject) seen.push_back(frame.points[i]);
    Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
    view.topLeftCorner<3, 3>() = world_to_camera.linear();
    const esf::PoseFit as_box = esf::fit_model(
        esf::sample_model_surface(esf::test::standing_box(0.09, 0.09, 0.12), 1.0, 3000, 1), view,
        {seen, &frame}, {});
    const esf::PoseFit as_can =
        esf::fit_model(esf::sample_model_surface(can, 1.0, 3000, 1), view, {seen, &frame}, {});
    EXPECT_LT(as_can.fit.violations, 0.05);  // pixels on the outline
    EXPECT_GT(as_box.fit.violations, as_can.fit.violations + 0.05);
    EXPECT_GT(as_can.fit.score(), as_box.fit.score());
}

TEST(FitModel, RejectsBadInput) {
    const esf::ModelSurface surface =
        esf::sample_model_surface(esf::test::standing_box(0.1, 0.1, 0.1), 1.0, 500, 0);
    const esf::Points two = {Eigen::Vector3f(0, 0, 1), Eigen::Vector3f(0.01f, 0, 1)};
    EXPECT_THROW(esf::fit_model(surface, Eigen::Matrix4d::Identity(), {two, nullptr}, {}),
                 std::invalid_argument);
    const esf::Points some = {Eigen::Vector3f(0, 0, 1), Eigen::Vector3f(0.01f, 0, 1),
                              Eigen::Vector3f(0, 0.01f, 1)};
    Eigen::Matrix4d nan = Eigen::Matrix4d::Identity();
    nan(0, 3) = std::nan("");
    EXPECT_THROW(esf::fit_model(surface, nan, {some, nullptr}, {}), std::invalid_argument);
    esf::PointCloud small;
    small.points.assign(4, Eigen::Vector3f(0, 0, 1));
    small.width = 2;
    small.height = 2;
    EXPECT_THROW(esf::fit_model(surface, Eigen::Matrix4d::Identity(), {some, &small}, {}),
                 std::invalid_argument);
    esf::VerificationOptions bad;
    bad.iterations = 0;
    EXPECT_THROW(esf::fit_model(surface, Eigen::Matrix4d::Identity(), {some, nullptr}, bad),
                 std::invalid_argument);
    // Each option refused at the values out of its range, accepted at one in it.
    const double not_a_number = std::numeric_limits<double>::quiet_NaN();
    const auto check_range = [](double esf::VerificationOptions::*option,
                                std::initializer_list<double> refused, double accepted) {
        esf::VerificationOptions o;
        for (const double value : refused) {
            o.*option = value;
            EXPECT_THROW(esf::validate(o), std::invalid_argument) << value;
        }
        o.*option = accepted;
        EXPECT_NO_THROW(esf::validate(o)) << accepted;
    };
    check_range(&esf::VerificationOptions::accept_score, {not_a_number, 3.0}, 2.0);
    check_range(&esf::VerificationOptions::prior_tolerance, {-0.1, not_a_number}, 0.0);
    check_range(&esf::VerificationOptions::shape_weight, {-0.1, not_a_number, 2.5}, 0.0);
}

}  // namespace
