#include "esf/report/point_picture.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "io/png_writer.hpp"

namespace esf {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

struct Rgb {
    double r, g, b;
};

/// Near (t = 0) and far (t = 1) colours of each tint.
constexpr std::array<std::array<Rgb, 2>, 3> kRamps = {{
    {{{40, 40, 40}, {205, 205, 205}}},   // grey
    {{{60, 130, 60}, {190, 225, 180}}},  // table
    {{{20, 60, 150}, {150, 190, 240}}},  // query
}};

/// The smallest square that closes the gaps between neighbouring points: the side of the
/// bounding box's share per distinct pixel hit, sqrt(box / hits), rounded up, 1 to 8. A cloud
/// denser than the picture gets 1 or 2; a sensor's pixel grid enlarged k times gets about k.
template <class Hits>
int auto_point_size(const Hits& hits, int w, int h) {
    if (hits.empty()) return 1;
    std::vector<bool> seen(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), false);
    int min_u = w, max_u = -1, min_v = h, max_v = -1;
    double distinct = 0.0;
    for (const auto& hit : hits) {
        const std::size_t i = static_cast<std::size_t>(hit.v) * static_cast<std::size_t>(w) +
                              static_cast<std::size_t>(hit.u);
        if (seen[i]) continue;
        seen[i] = true;
        distinct += 1.0;
        min_u = std::min(min_u, hit.u);
        max_u = std::max(max_u, hit.u);
        min_v = std::min(min_v, hit.v);
        max_v = std::max(max_v, hit.v);
    }
    const double box = static_cast<double>(max_u - min_u + 1) * (max_v - min_v + 1);
    return std::clamp(static_cast<int>(std::ceil(std::sqrt(box / distinct))), 1, 8);
}

}  // namespace

std::optional<Eigen::Vector2d> PictureProjection::project(const Eigen::Vector3f& p) const {
    if (!p.allFinite() || p.z() <= 0.0f) return std::nullopt;
    const double x = p.x(), y = p.y(), z = p.z();
    return Eigen::Vector2d(fx * (x / z) + cx, fy * (y / z) + cy);
}

PictureProjection fit_projection(std::span<const Eigen::Vector3f> points, int width, int height,
                                 int margin) {
    if (margin < 0 || width - 2 * margin < 1 || height - 2 * margin < 1)
        throw std::invalid_argument("picture: " + std::to_string(width) + " x " +
                                    std::to_string(height) + " pixels with a margin of " +
                                    std::to_string(margin) + " leave no pixel");
    // Bounds of the normalised image coordinates x / z, y / z.
    double min_u = kInfinity, max_u = -kInfinity, min_v = kInfinity, max_v = -kInfinity;
    for (const Eigen::Vector3f& p : points) {
        if (!p.allFinite() || p.z() <= 0.0f) continue;
        const double z = p.z(), u = p.x() / z, v = p.y() / z;
        min_u = std::min(min_u, u);
        max_u = std::max(max_u, u);
        min_v = std::min(min_v, v);
        max_v = std::max(max_v, v);
    }
    PictureProjection q;
    q.width = width;
    q.height = height;
    const double inner_w = width - 2 * margin, inner_h = height - 2 * margin;
    double f = inner_w;  // any focal length does for no point or a single ray
    if (min_u <= max_u) {
        const double span_u = max_u - min_u, span_v = max_v - min_v;
        // The extreme points land at most inner - 1 pixels apart, inside the margins.
        const double fu = span_u > 0.0 ? (inner_w - 1.0) / span_u : kInfinity;
        const double fv = span_v > 0.0 ? (inner_h - 1.0) / span_v : kInfinity;
        if (std::isfinite(std::min(fu, fv))) f = std::max(std::min(fu, fv), 1e-9);
    } else {
        min_u = max_u = min_v = max_v = 0.0;
    }
    q.fx = q.fy = f;
    q.cx = width / 2.0 - f * (min_u + max_u) / 2.0;
    q.cy = height / 2.0 - f * (min_v + max_v) / 2.0;
    return q;
}

PointPicture draw_points(std::span<const Eigen::Vector3f> points,
                         const PointPictureOptions& options, std::span<const std::uint8_t> tints) {
    if (options.point_size < 0)
        throw std::invalid_argument("picture: point_size must be 0 (auto) or more, got " +
                                    std::to_string(options.point_size));
    if (!tints.empty() && tints.size() != points.size())
        throw std::invalid_argument("picture: " + std::to_string(tints.size()) + " tints for " +
                                    std::to_string(points.size()) + " points");
    PointPicture out;
    out.projection = options.projection
                         ? *options.projection
                         : fit_projection(points, options.width, options.height, options.margin);
    const int w = out.projection.width, h = out.projection.height;
    if (w < 1 || h < 1)
        throw std::invalid_argument("picture: " + std::to_string(w) + " x " + std::to_string(h) +
                                    " pixels");
    out.width = w;
    out.height = h;
    const auto pixels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
    // The pixel of every point that lands inside.
    struct Hit {
        std::size_t point;
        int u, v;
    };
    std::vector<Hit> hits;
    hits.reserve(points.size());
    for (std::size_t n = 0; n < points.size(); ++n) {
        const auto uv = out.projection.project(points[n]);
        if (!uv) continue;
        const double fu = std::floor(uv->x()), fv = std::floor(uv->y());
        if (fu < 0.0 || fv < 0.0 || fu >= w || fv >= h) continue;
        hits.push_back({n, static_cast<int>(fu), static_cast<int>(fv)});
    }
    out.drawn = hits.size();
    const int size = options.point_size ? options.point_size : auto_point_size(hits, w, h);
    std::vector<float> depth(pixels, std::numeric_limits<float>::infinity());
    std::vector<std::uint8_t> tint(pixels, 0);
    float near = std::numeric_limits<float>::infinity(), far = -near;
    const int lo = (size - 1) / 2, hi = size / 2;
    for (const Hit& hit : hits) {
        const float z = points[hit.point].z();
        near = std::min(near, z);
        far = std::max(far, z);
        const std::uint8_t t = tints.empty() ? kTintGrey : tints[hit.point];
        for (int y = std::max(hit.v - lo, 0); y <= std::min(hit.v + hi, h - 1); ++y)
            for (int x = std::max(hit.u - lo, 0); x <= std::min(hit.u + hi, w - 1); ++x) {
                const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
                                      static_cast<std::size_t>(x);
                if (z < depth[i]) {
                    depth[i] = z;
                    tint[i] = std::min<std::uint8_t>(t, kRamps.size() - 1);
                }
            }
    }
    out.rgb.assign(pixels * 3, 255);
    const double range = far > near ? static_cast<double>(far) - near : 1.0;
    for (std::size_t i = 0; i < pixels; ++i) {
        if (!std::isfinite(depth[i])) continue;
        const double t = (depth[i] - near) / range;
        const auto& ramp = kRamps[tint[i]];
        auto mix = [t](double a, double b) {
            return static_cast<std::uint8_t>(std::lround(a + t * (b - a)));
        };
        out.rgb[3 * i] = mix(ramp[0].r, ramp[1].r);
        out.rgb[3 * i + 1] = mix(ramp[0].g, ramp[1].g);
        out.rgb[3 * i + 2] = mix(ramp[0].b, ramp[1].b);
    }
    return out;
}

std::vector<std::uint8_t> picture_png(const PointPicture& picture) {
    return detail::encode_png(picture.rgb, static_cast<std::uint32_t>(picture.width),
                              static_cast<std::uint32_t>(picture.height), 3, 8);
}

std::string png_data_uri(std::span<const std::uint8_t> png) {
    static const char* const kTable =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out = "data:image/png;base64,";
    out.reserve(out.size() + (png.size() + 2) / 3 * 4);
    for (std::size_t i = 0; i < png.size(); i += 3) {
        const std::uint32_t b0 = png[i];
        const std::uint32_t b1 = i + 1 < png.size() ? png[i + 1] : 0;
        const std::uint32_t b2 = i + 2 < png.size() ? png[i + 2] : 0;
        const std::uint32_t v = (b0 << 16) | (b1 << 8) | b2;
        out += kTable[(v >> 18) & 63];
        out += kTable[(v >> 12) & 63];
        out += i + 1 < png.size() ? kTable[(v >> 6) & 63] : '=';
        out += i + 2 < png.size() ? kTable[v & 63] : '=';
    }
    return out;
}

}  // namespace esf
