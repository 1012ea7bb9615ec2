// Point pictures: hand-placed points and the pixels they light, the fitted projection's
// margins, depth order and shades, tints, PNG and data URI encoding, and the error messages.

#include "esf/report/point_picture.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using Rgb = std::array<int, 3>;

Rgb pixel(const esf::PointPicture& p, int x, int y) {
    const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(p.width) +
                           static_cast<std::size_t>(x)) *
                          3;
    return {p.rgb[i], p.rgb[i + 1], p.rgb[i + 2]};
}

const Rgb kWhite = {255, 255, 255};

std::size_t lit_pixels(const esf::PointPicture& p) {
    std::size_t lit = 0;
    for (int y = 0; y < p.height; ++y)
        for (int x = 0; x < p.width; ++x) lit += pixel(p, x, y) != kWhite;
    return lit;
}

/// 160 x 120, f = 100, principal point at the picture's centre (80, 60).
esf::PointPictureOptions fixed_camera(int point_size = 1) {
    esf::PointPictureOptions o;
    o.projection = esf::PictureProjection{};  // the defaults: 160 x 120, f 100, (80, 60)
    o.point_size = point_size;
    return o;
}

TEST(PointPicture, PointOnTheAxisLightsTheCentrePixelOnly) {
    const std::vector<Eigen::Vector3f> points = {{0.0f, 0.0f, 1.0f}};
    const esf::PointPicture p = esf::draw_points(points, fixed_camera());
    ASSERT_EQ(p.width, 160);
    ASSERT_EQ(p.height, 120);
    ASSERT_EQ(p.rgb.size(), 160u * 120u * 3u);
    EXPECT_EQ(p.drawn, 1u);
    EXPECT_EQ(pixel(p, 80, 60), (Rgb{40, 40, 40}));  // the grey ramp's near end
    EXPECT_EQ(lit_pixels(p), 1u);
}

TEST(PointPicture, PinholeProjectionPutsPointsWhereHandComputed) {
    // x = 0.2, z = 1: u = 100 * 0.2 + 80 = 100; y = 0.1, z = 2: v = 100 * 0.05 + 60 = 65.
    const std::vector<Eigen::Vector3f> points = {{0.2f, 0.0f, 1.0f}, {0.0f, 0.1f, 2.0f}};
    const esf::PointPicture p = esf::draw_points(points, fixed_camera());
    EXPECT_NE(pixel(p, 100, 60), kWhite);
    EXPECT_NE(pixel(p, 80, 65), kWhite);
    EXPECT_EQ(lit_pixels(p), 2u);
    // Nearer is darker: z = 1 is the nearest (40), z = 2 the farthest (205).
    EXPECT_EQ(pixel(p, 100, 60), (Rgb{40, 40, 40}));
    EXPECT_EQ(pixel(p, 80, 65), (Rgb{205, 205, 205}));
}

TEST(PointPicture, NearestPointOfAPixelWins) {
    // Both on the optical axis; the far one is drawn last and must not cover the near one.
    const std::vector<Eigen::Vector3f> points = {
        {0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 3.0f}, {0.3f, 0.0f, 3.0f}};
    const esf::PointPicture p = esf::draw_points(points, fixed_camera());
    EXPECT_EQ(p.drawn, 3u);
    EXPECT_EQ(pixel(p, 80, 60), (Rgb{40, 40, 40}));
    EXPECT_EQ(pixel(p, 90, 60), (Rgb{205, 205, 205}));  // u = 100 * 0.1 + 80
}

TEST(PointPicture, PointsBehindTheCameraOutsideOrNotFiniteAreNotDrawn) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<Eigen::Vector3f> points = {
        {0.0f, 0.0f, -1.0f}, {0.0f, 0.0f, 0.0f}, {nan, 0.0f, 1.0f}, {5.0f, 0.0f, 1.0f}};
    const esf::PointPicture p = esf::draw_points(points, fixed_camera());
    EXPECT_EQ(p.drawn, 0u);
    EXPECT_EQ(lit_pixels(p), 0u);
}

TEST(PointPicture, PointSizeDrawsASquareAroundThePixel) {
    const std::vector<Eigen::Vector3f> points = {{0.0f, 0.0f, 1.0f}};
    const esf::PointPicture p3 = esf::draw_points(points, fixed_camera(3));
    EXPECT_EQ(lit_pixels(p3), 9u);
    for (int y = 59; y <= 61; ++y)
        for (int x = 79; x <= 81; ++x) EXPECT_NE(pixel(p3, x, y), kWhite) << x << ", " << y;
    // An even size extends right and down: pixels 80..81 x 60..61.
    const esf::PointPicture p2 = esf::draw_points(points, fixed_camera(2));
    EXPECT_EQ(lit_pixels(p2), 4u);
    EXPECT_NE(pixel(p2, 81, 61), kWhite);
    EXPECT_EQ(pixel(p2, 79, 59), kWhite);
}

TEST(PointPicture, AutomaticPointSizeClosesTheGapsOfASparseGrid) {
    // A 5 x 5 grid of points 4 pixels apart (u, v = 72 .. 88 and 52 .. 68): its box is
    // 17 x 17 = 289 pixels for 25 hits, sqrt(289 / 25) = 3.4 -> squares of 4 that tile it.
    std::vector<Eigen::Vector3f> points;
    for (int j = -2; j <= 2; ++j)
        for (int i = -2; i <= 2; ++i)
            points.emplace_back(0.04f * static_cast<float>(i) + 0.001f,
                                0.04f * static_cast<float>(j) + 0.001f, 1.0f);
    esf::PointPictureOptions o = fixed_camera(0);
    const esf::PointPicture p = esf::draw_points(points, o);
    EXPECT_EQ(p.drawn, 25u);
    EXPECT_EQ(lit_pixels(p), 20u * 20u);  // 71 .. 90 in both directions
    for (int y = 51; y <= 70; ++y)
        for (int x = 71; x <= 90; ++x) EXPECT_NE(pixel(p, x, y), kWhite) << x << ", " << y;
    // A dense cloud (a point per pixel) keeps single pixels.
    std::vector<Eigen::Vector3f> dense;
    for (int j = 0; j < 10; ++j)
        for (int i = 0; i < 10; ++i)
            dense.emplace_back(0.01f * static_cast<float>(i) + 0.0005f,
                               0.01f * static_cast<float>(j) + 0.0005f, 1.0f);
    EXPECT_EQ(lit_pixels(esf::draw_points(dense, o)), 100u);
}

TEST(PointPicture, TintsPickTheRamp) {
    const std::vector<Eigen::Vector3f> points = {{0.0f, 0.0f, 1.0f}, {0.2f, 0.0f, 1.0f}};
    const std::vector<std::uint8_t> tints = {esf::kTintTable, esf::kTintBlue};
    const esf::PointPicture p = esf::draw_points(points, fixed_camera(), tints);
    EXPECT_EQ(pixel(p, 80, 60), (Rgb{60, 130, 60}));
    EXPECT_EQ(pixel(p, 100, 60), (Rgb{20, 60, 150}));
}

TEST(FitProjection, SinglePointLandsOnTheCentre) {
    const std::vector<Eigen::Vector3f> points = {{0.25f, -0.5f, 2.0f}};
    esf::PointPictureOptions o;  // fitted, 160 x 120
    o.point_size = 1;
    const esf::PointPicture p = esf::draw_points(points, o);
    EXPECT_EQ(p.drawn, 1u);
    EXPECT_NE(pixel(p, 80, 60), kWhite);
    EXPECT_EQ(lit_pixels(p), 1u);
}

TEST(FitProjection, ExtremePointsLandInsideTheMargins) {
    // u = x / z spans [-0.5, 0.5]; v = 0: 152 inner columns, f = 151, centre 80:
    // u = 80 -+ 75.5 -> pixels 4 and 155, the first and last inside a margin of 4.
    const std::vector<Eigen::Vector3f> points = {{-1.0f, 0.0f, 2.0f}, {1.0f, 0.0f, 2.0f}};
    const esf::PictureProjection q = esf::fit_projection(points, 160, 120, 4);
    EXPECT_DOUBLE_EQ(q.fx, 151.0);
    EXPECT_DOUBLE_EQ(q.fy, 151.0);
    esf::PointPictureOptions o;
    o.point_size = 1;
    const esf::PointPicture p = esf::draw_points(points, o);
    EXPECT_NE(pixel(p, 4, 60), kWhite);
    EXPECT_NE(pixel(p, 155, 60), kWhite);
    EXPECT_EQ(lit_pixels(p), 2u);
    // A tall cloud is limited by the height: v spans [-1, 1] over 111 pixels.
    const std::vector<Eigen::Vector3f> tall = {{0.0f, -1.0f, 1.0f}, {0.0f, 1.0f, 1.0f}};
    EXPECT_DOUBLE_EQ(esf::fit_projection(tall, 160, 120, 4).fy, 55.5);
}

TEST(PointPicture, DataUriAndPng) {
    // RFC 4648 test vectors.
    const std::vector<std::uint8_t> man = {'M', 'a', 'n'}, m = {'M'}, ma = {'M', 'a'};
    EXPECT_EQ(esf::png_data_uri(man), "data:image/png;base64,TWFu");
    EXPECT_EQ(esf::png_data_uri(m), "data:image/png;base64,TQ==");
    EXPECT_EQ(esf::png_data_uri(ma), "data:image/png;base64,TWE=");
    const std::vector<Eigen::Vector3f> points = {{0.0f, 0.0f, 1.0f}};
    const std::vector<std::uint8_t> png = esf::picture_png(esf::draw_points(points));
    ASSERT_GT(png.size(), 24u);
    EXPECT_EQ(png[1], 'P');
    EXPECT_EQ(png[2], 'N');
    EXPECT_EQ(png[3], 'G');
    // IHDR: width and height, big-endian, at bytes 16 and 20.
    EXPECT_EQ((png[18] << 8) | png[19], 160);
    EXPECT_EQ((png[22] << 8) | png[23], 120);
}

TEST(PointPicture, BadOptionsThrowNamingTheValue) {
    const std::vector<Eigen::Vector3f> points = {{0.0f, 0.0f, 1.0f}};
    esf::PointPictureOptions o;
    o.point_size = -1;
    try {
        esf::draw_points(points, o);
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("point_size must be 0 (auto) or more, got -1"),
                  std::string::npos)
            << e.what();
    }
    const std::vector<std::uint8_t> tints = {0, 0};
    try {
        esf::draw_points(points, {}, tints);
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("2 tints for 1 points"), std::string::npos)
            << e.what();
    }
    try {
        esf::fit_projection(points, 8, 8, 4);
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("8 x 8 pixels with a margin of 4"), std::string::npos)
            << e.what();
    }
}

}  // namespace
