#pragma once
// Small depth-shaded pictures of points, for report pages: points in a camera frame (x right,
// y down, z forward, as a depth sensor gives them) are projected through a pinhole onto a
// width x height RGB raster, the nearest point of each pixel wins, and its depth picks the shade
// (near = dark, far = light; background white). Pictures are encoded as PNG and embedded in
// pages as data URIs, so a page needs no other file.
//
// Reentrant; no global state.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "esf/core/point_cloud.hpp"

namespace esf {

/// A pinhole camera onto a picture: pixel (u, v) = (fx x / z + cx, fy y / z + cy); pixel (i, j)
/// covers [i, i + 1) x [j, j + 1), so a point projecting to (80.5, 60.5) lights pixel (80, 60).
struct PictureProjection {
    int width = 160;
    int height = 120;
    double fx = 100.0, fy = 100.0, cx = 80.0, cy = 60.0;

    /// Where `p` lands (continuous pixel coordinates); std::nullopt for z <= 0 or a non-finite
    /// point. The result may lie outside the picture.
    std::optional<Eigen::Vector2d> project(const Eigen::Vector3f& p) const;
};

/// The projection that fits the finite points in front of the camera (z > 0) into a width x
/// height picture with `margin` pixels free on every side, one scale for both axes, centred.
/// A single point (or points along one ray) lands on the picture's centre. Throws
/// std::invalid_argument for a picture smaller than 1 x 1 after the margins.
PictureProjection fit_projection(std::span<const Eigen::Vector3f> points, int width, int height,
                                 int margin = 4);

struct PointPictureOptions {
    int width = 160;
    int height = 120;
    int margin = 4;  ///< for the fitted projection
    /// Side of the square drawn per point (pixels), centred on the point's pixel; 0 = auto: about
    /// the spacing of neighbouring points in the picture, sqrt(bounding box / pixels hit)
    /// rounded up, 1 to 8, so that sparse clouds (a sensor's grid enlarged) show as surfaces.
    int point_size = 0;
    /// When set, used instead of fit_projection() (its width and height win over the above).
    std::optional<PictureProjection> projection;
};

/// An 8-bit RGB raster, rows top to bottom.
struct PointPicture {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgb;  ///< width * height * 3
    std::size_t drawn = 0;          ///< points that landed inside the picture
    PictureProjection projection;   ///< the projection used
};

/// Tints of draw_points().
inline constexpr std::uint8_t kTintGrey = 0;   ///< grey ramp (objects, the scene)
inline constexpr std::uint8_t kTintTable = 1;  ///< green ramp (a table plane)
inline constexpr std::uint8_t kTintBlue = 2;   ///< blue ramp (a query)

/// Draws the points: each one that projects inside the picture paints a point_size square, the
/// nearest (smallest z) wins where they overlap; shades run from dark (the nearest drawn point)
/// to light (the farthest). `tints` is empty (all kTintGrey) or holds one tint per point.
/// Throws std::invalid_argument for a size below 1 x 1, point_size < 0, or tints of another
/// length than points.
PointPicture draw_points(std::span<const Eigen::Vector3f> points,
                         const PointPictureOptions& options = {},
                         std::span<const std::uint8_t> tints = {});

/// PNG bytes of a picture (8-bit RGB).
std::vector<std::uint8_t> picture_png(const PointPicture& picture);

/// "data:image/png;base64,..." of PNG bytes, for an <img src> or an SVG <image href>.
std::string png_data_uri(std::span<const std::uint8_t> png);

}  // namespace esf
