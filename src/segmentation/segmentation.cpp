#include "esf/segmentation/segmentation.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/convex_hull_2d.hpp"
#include "core/number_text.hpp"
#include "core/pixel_rows.hpp"
#include "esf/core/parallel.hpp"
#include "segmentation/container_parts.hpp"
#include "segmentation/euclidean_clusters.hpp"
#include "segmentation/occluded_parts.hpp"
#include "segmentation/plane_fit.hpp"

namespace esf {

namespace {

// Fixed work split (independent of the thread count), so reductions add up in the same order.
constexpr std::size_t kChunks = 64;
// Pixels from the image border within which a cluster may be cut off.
constexpr std::uint32_t kBorderMargin = 2;
// A table stands at least this high above the floor (m); what stands on a table and is flat and
// large enough to pass for one is lower.
constexpr float kFurnitureHeight = 0.3f;
// Planes within 10 degrees of each other are parallel.
constexpr float kParallelCosine = 0.985f;

std::string format_metres(double value) { return detail::significant_text(value, 3) + " m"; }

std::size_t chunk_begin(std::size_t chunk, std::size_t count) { return chunk * count / kChunks; }

using detail::convex_hull;
using detail::ConvexRegion;
using detail::min_area_rectangle;
using detail::monotone_chain;
using detail::Octagon;
using detail::Rectangle;
using detail::Vec2;
using Hypothesis = detail::PlaneHypothesis;
using detail::facing;
using detail::plane_basis;
using detail::ransac_plane;
using detail::refit_plane;

// ---------------------------------------------------------------------------------------------

/// A cluster's centroid, size and length axis from its points (Cluster).
void measure_cluster(Cluster& cluster, const Plane& plane) {
    const auto [u, w] = plane_basis(plane.normal);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    float top = -std::numeric_limits<float>::infinity();
    std::vector<Vec2> projected;
    projected.reserve(cluster.points.size());
    for (const Eigen::Vector3f& p : cluster.points) {
        sum += p.cast<double>();
        top = std::max(top, plane.height(p));
        projected.emplace_back(u.dot(p), w.dot(p));
    }
    cluster.centroid = (sum / static_cast<double>(cluster.points.size())).cast<float>();
    const Rectangle box = min_area_rectangle(convex_hull(projected));
    cluster.size = Eigen::Vector3f(box.length, box.width, top);
    cluster.length_axis = (box.length_axis.x() * u + box.length_axis.y() * w).normalized();
}

/// Step 6b (organised frames): each cluster takes in the pixels next to it, repeatedly, that
/// stand below min_height but above the rim floor, without a depth step from the pixel they
/// grow from; pixels go to the cluster that reaches them first (breadth first from every
/// cluster's pixels in cluster order). Each cluster's indices stay ascending.
void grow_rims(std::span<const Eigen::Vector3f> points, std::uint32_t width, std::uint32_t height,
               const Plane& plane, const SegmentationOptions& options,
               std::vector<Cluster>& clusters) {
    constexpr float kMaxStep = 0.01f;  // m of depth between neighbouring pixels of one surface
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> owner(points.size(), kNone), queue;
    for (std::uint32_t c = 0; c < clusters.size(); ++c)
        for (const std::uint32_t i : clusters[c].indices) {
            owner[i] = c;
            queue.push_back(i);
        }
    std::vector<std::vector<std::uint32_t>> grown(clusters.size());
    for (std::size_t head = 0; head < queue.size(); ++head) {
        const std::uint32_t i = queue[head];
        const std::uint32_t row = i / width, col = i % width;
        const std::array<std::uint32_t, 4> next = {
            row > 0 ? i - width : i, row + 1 < height ? i + width : i, col > 0 ? i - 1 : i,
            col + 1 < width ? i + 1 : i};
        for (const std::uint32_t j : next) {
            if (j == i || owner[j] != kNone || !points[j].allFinite()) continue;
            const float range = (points[j] - options.viewpoint).norm();
            const float floor = std::max(options.rim_height, options.rim_noise * range * range);
            const float h = plane.height(points[j]);
            if (!(h > floor && h <= options.min_height)) continue;
            if (std::abs(range - (points[i] - options.viewpoint).norm()) > kMaxStep) continue;
            owner[j] = owner[i];
            grown[owner[i]].push_back(j);
            queue.push_back(j);
        }
    }
    for (std::size_t c = 0; c < clusters.size(); ++c) {
        if (grown[c].empty()) continue;
        std::vector<std::uint32_t>& indices = clusters[c].indices;
        indices.insert(indices.end(), grown[c].begin(), grown[c].end());
        std::sort(indices.begin(), indices.end());
        clusters[c].points.clear();
        for (const std::uint32_t i : indices) clusters[c].points.push_back(points[i]);
    }
}

SegmentationResult segment(std::span<const Eigen::Vector3f> points, std::uint32_t width,
                           std::uint32_t height, const SegmentationOptions& options) {
    validate(options);
    if (points.empty()) throw std::invalid_argument("segment_scene: the cloud is empty");
    if (points.size() > std::numeric_limits<std::uint32_t>::max())
        throw std::invalid_argument("segment_scene: more than 2^32 - 1 points");
    const bool organised = height > 1 && static_cast<std::size_t>(width) * height == points.size();

    if (!organised && height == 1 && options.image_camera) {
        // A depth image with its invalid pixels dropped: segmented as the image, the clusters
        // then mapped back to the input's indices and order.
        std::vector<std::uint32_t> source;
        if (const std::optional<PointCloud> image =
                depth_image_of(points, *options.image_camera, &source)) {
            SegmentationResult result =
                segment(image->points, image->width, image->height, options);
            result.finite_points = 0;
            for (const Eigen::Vector3f& p : points) result.finite_points += p.allFinite();
            for (Cluster& cluster : result.clusters) {
                for (std::uint32_t& index : cluster.indices) index = source[index];
                std::vector<std::size_t> order(cluster.indices.size());
                std::iota(order.begin(), order.end(), std::size_t{0});
                std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
                    return cluster.indices[a] < cluster.indices[b];
                });
                std::vector<std::uint32_t> indices(order.size());
                Points in_order(order.size());
                for (std::size_t k = 0; k < order.size(); ++k) {
                    indices[k] = cluster.indices[order[k]];
                    in_order[k] = cluster.points[order[k]];
                }
                cluster.indices = std::move(indices);
                cluster.points = std::move(in_order);
            }
            return result;
        }
    }

    std::vector<std::uint32_t> finite;
    finite.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        if (points[i].allFinite()) finite.push_back(static_cast<std::uint32_t>(i));
    if (finite.empty())
        throw std::invalid_argument("segment_scene: the cloud has no finite points (" +
                                    std::to_string(points.size()) + " points, all NaN or inf)");

    SegmentationResult result;
    result.finite_points = finite.size();

    // 1. RANSAC on an even subsample.
    const std::size_t sample_count = std::min(finite.size(), options.plane_samples);
    std::vector<Eigen::Vector3f> samples(sample_count);
    for (std::size_t i = 0; i < sample_count; ++i)
        samples[i] = points[finite[i * finite.size() / sample_count]];
    const Hypothesis best = ransac_plane(samples, options);
    if (best.inliers == 0) {
        result.message = "no dominant plane: fewer than 3 non-collinear points";
        return result;
    }

    // 2. Least-squares refit to the sampled inliers; orient to the viewpoint.
    Plane plane = facing(refit_plane(samples, Plane{best.normal, best.d}, options.plane_distance),
                         options.viewpoint);
    // 2b. Past a table's edge the floor can hold more points than the table: a parallel plane
    // well above the dominant one (furniture height) that holds a share of the points a table
    // would is the table the objects stand on.
    {
        std::vector<Eigen::Vector3f> above;
        for (const Eigen::Vector3f& p : samples)
            if (plane.height(p) > kFurnitureHeight) above.push_back(p);
        const double needed = options.min_plane_fraction * static_cast<double>(samples.size());
        if (static_cast<double>(above.size()) >= needed && above.size() >= 3) {
            const Hypothesis higher = ransac_plane(above, options);
            if (higher.inliers > 0 && static_cast<double>(higher.inliers) >= needed &&
                std::abs(higher.normal.dot(plane.normal)) >= kParallelCosine)
                plane = facing(
                    refit_plane(above, Plane{higher.normal, higher.d}, options.plane_distance),
                    options.viewpoint);
        }
    }
    result.plane = plane;

    // 3./4. One pass: table points (projected, for the hull) and object candidates. In an
    // organised frame the table's hull needs only each image row's first and last table pixel:
    // the table lies in front of the camera, so the projection from the plane to the image
    // keeps convexity, and a pixel between two table pixels of its row is never a hull vertex.
    const auto [u, w] = plane_basis(plane.normal);
    struct Part {
        std::size_t table_points = 0;
        std::vector<Vec2> table;
        Octagon octagon;
        std::vector<Vec2> outside;
        std::vector<std::uint32_t> candidates;
    };
    std::vector<Part> parts(kChunks);
    parallel_for(kChunks, options.threads, [&](std::size_t c) {
        Part& part = parts[c];
        std::uint32_t row = std::numeric_limits<std::uint32_t>::max();
        std::uint32_t first = 0, last = 0;
        std::size_t row_end = 0;  // first index after `row`
        auto close_row = [&] {
            if (row == std::numeric_limits<std::uint32_t>::max()) return;
            part.outside.emplace_back(u.dot(points[first]), w.dot(points[first]));
            if (last != first) part.outside.emplace_back(u.dot(points[last]), w.dot(points[last]));
        };
        for (std::size_t k = chunk_begin(c, finite.size()); k < chunk_begin(c + 1, finite.size());
             ++k) {
            const Eigen::Vector3f& p = points[finite[k]];
            const float h = plane.height(p);
            if (std::abs(h) <= options.plane_distance) {
                ++part.table_points;
                if (organised) {
                    if (finite[k] >= row_end) {  // a new row (indices ascend): divide only here
                        close_row();
                        row = finite[k] / width;
                        row_end = (static_cast<std::size_t>(row) + 1) * width;
                        first = finite[k];
                    }
                    last = finite[k];
                } else {
                    part.table.emplace_back(u.dot(p), w.dot(p));
                    part.octagon.add(part.table.back());
                }
            }
            if (h > options.min_height && h <= options.max_height)
                part.candidates.push_back(finite[k]);
        }
        close_row();
    });
    Octagon octagon;
    for (const Part& part : parts) {
        result.plane_inliers += part.table_points;
        octagon.merge(part.octagon);
    }
    const double needed_points =
        std::max(static_cast<double>(options.min_plane_points),
                 options.min_plane_fraction * static_cast<double>(finite.size()));
    if (static_cast<double>(result.plane_inliers) < needed_points) {
        result.message = "no dominant plane: the best plane holds " +
                         std::to_string(result.plane_inliers) + " of " +
                         std::to_string(finite.size()) + " finite points (needs " +
                         std::to_string(static_cast<std::size_t>(std::ceil(needed_points))) + ")";
        return result;
    }
    if (!organised)
        parallel_for(kChunks, options.threads, [&](std::size_t c) {
            octagon.append_outside(parts[c].table, parts[c].outside);
        });
    std::vector<Vec2> hull_candidates;
    std::vector<std::uint32_t> candidates;
    for (Part& part : parts) {
        hull_candidates.insert(hull_candidates.end(), part.outside.begin(), part.outside.end());
        candidates.insert(candidates.end(), part.candidates.begin(), part.candidates.end());
        part = Part{};
    }
    const std::vector<Vec2> hull = monotone_chain(std::move(hull_candidates));
    if (hull.size() < 3) {
        result.message = "no dominant plane: the plane's points are collinear";
        return result;
    }
    result.plane_found = true;

    // Keep the candidates whose projection lies inside the hull (the polygonal prism), or within
    // hull_margin of it.
    const ConvexRegion table(hull);
    std::vector<std::uint8_t> keep(candidates.size());
    parallel_for(kChunks, options.threads, [&](std::size_t c) {
        for (std::size_t k = chunk_begin(c, candidates.size());
             k < chunk_begin(c + 1, candidates.size()); ++k) {
            const Eigen::Vector3f& p = points[candidates[k]];
            const Vec2 q(u.dot(p), w.dot(p));
            keep[k] = table.contains(q, options.hull_margin) ? 1 : 0;
        }
    });
    std::size_t kept = 0;
    for (std::size_t k = 0; k < candidates.size(); ++k)
        if (keep[k]) candidates[kept++] = candidates[k];
    candidates.resize(kept);

    auto no_objects = [&](const std::string& why) {
        result.message = "no objects above the plane: " + why;
        return result;
    };
    if (candidates.empty())
        return no_objects("no points between " + format_metres(options.min_height) + " and " +
                          format_metres(options.max_height) + " above it inside its hull");

    // 5. Grouping of the candidates.
    std::vector<Eigen::Vector3f> candidate_points(candidates.size());
    for (std::size_t k = 0; k < candidates.size(); ++k) candidate_points[k] = points[candidates[k]];
    std::vector<std::uint32_t> component;
    if (options.grouping == Grouping::kConvexity) {
        SurfacePatchOptions patch_options = options.patches;
        patch_options.viewpoint = options.viewpoint;
        const PatchGraph graph =
            organised ? image_patches(points, width, height, candidates, patch_options)
                      : voxel_patches(points, candidates, patch_options);
        const std::vector<std::uint32_t> segment = convex_segments(graph, options.convexity);
        component.resize(candidates.size());
        for (std::size_t k = 0; k < candidates.size(); ++k)
            component[k] = segment[graph.patch_of[k]];
        if (organised && options.join_occluded_parts)
            detail::join_occluded_parts(points, width, height, candidates, component,
                                        options.viewpoint, plane.normal, plane.d);
        if (options.join_container_parts)
            detail::join_container_parts(candidate_points, component, plane.normal, plane.d);
    } else {
        for (const std::uint32_t i : candidates)
            if (!detail::fits_clustering_grid(points[i], options.cluster_tolerance))
                throw std::invalid_argument(
                    "segment_scene: coordinates too large for the clustering grid (point " +
                    std::to_string(i) +
                    "; at most 2^20 cells of cluster_tolerance / sqrt(3) from "
                    "the origin per axis)");
        component = detail::euclidean_components(candidate_points, options.cluster_tolerance);
    }

    // 6. Clusters within the size limits.
    const std::uint32_t component_count = *std::max_element(component.begin(), component.end()) + 1;
    std::vector<std::size_t> component_points(component_count, 0);
    for (const std::uint32_t c : component) ++component_points[c];
    constexpr std::uint32_t kDropped = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> cluster_of(component_count, kDropped);
    std::uint32_t cluster_count = 0;
    for (std::uint32_t c = 0; c < component_count; ++c)
        if (component_points[c] >= options.min_cluster_points &&
            component_points[c] <= options.max_cluster_points)
            cluster_of[c] = cluster_count++;
    if (cluster_count == 0) {
        const std::size_t largest =
            *std::max_element(component_points.begin(), component_points.end());
        return no_objects(std::to_string(candidates.size()) + " points above it form " +
                          std::to_string(component_count) + " groups, the largest of " +
                          std::to_string(largest) + " points (clusters need " +
                          std::to_string(options.min_cluster_points) + " to " +
                          std::to_string(options.max_cluster_points) + ")");
    }
    std::vector<Cluster> clusters(cluster_count);
    for (std::uint32_t c = 0; c < component_count; ++c)
        if (cluster_of[c] != kDropped) {
            clusters[cluster_of[c]].indices.reserve(component_points[c]);
            clusters[cluster_of[c]].points.reserve(component_points[c]);
        }
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        const std::uint32_t cluster = cluster_of[component[k]];
        if (cluster == kDropped) continue;
        clusters[cluster].indices.push_back(candidates[k]);
        clusters[cluster].points.push_back(candidate_points[k]);
    }

    if (organised && options.rim_height < options.min_height)
        grow_rims(points, width, height, plane, options, clusters);
    if (organised && options.join_container_floors)
        detail::join_container_floors(points, width, plane, options.min_height, clusters);

    parallel_for(clusters.size(), options.threads, [&](std::size_t c) {
        Cluster& cluster = clusters[c];
        measure_cluster(cluster, plane);
        const float top = cluster.size.z();

        std::string why;
        if (organised) {
            detail::PixelRows rows(width);
            for (const std::uint32_t i : cluster.indices) {
                rows.seek(i);
                const std::uint32_t row = rows.row(), col = rows.col();
                if (row < kBorderMargin || col < kBorderMargin || row + kBorderMargin >= height ||
                    col + kBorderMargin >= width) {
                    why = "touches the image border";
                    break;
                }
            }
        }
        if (top >= options.max_height - options.cluster_tolerance) {
            if (!why.empty()) why += "; ";
            why += "reaches the height limit of " + format_metres(options.max_height);
        }
        if (!why.empty()) {
            cluster.status = ClusterStatus::kMaybeTruncated;
            cluster.message = "may be cut off: " + why;
        }
    });

    std::sort(clusters.begin(), clusters.end(), [](const Cluster& a, const Cluster& b) {
        if (a.points.size() != b.points.size()) return a.points.size() > b.points.size();
        for (int k = 0; k < 3; ++k)
            if (a.centroid[k] != b.centroid[k]) return a.centroid[k] < b.centroid[k];
        return a.indices.front() < b.indices.front();
    });
    result.clusters = std::move(clusters);
    result.message = std::to_string(result.clusters.size()) +
                     (result.clusters.size() == 1 ? " object" : " objects") + " above the plane";
    return result;
}

}  // namespace

Cluster merge_clusters(const Cluster& a, const Cluster& b, const Plane& plane) {
    if (a.points.empty() || b.points.empty())
        throw std::invalid_argument("merge_clusters: a cluster without points");
    Cluster out = a;
    out.points.insert(out.points.end(), b.points.begin(), b.points.end());
    out.indices.insert(out.indices.end(), b.indices.begin(), b.indices.end());
    measure_cluster(out, plane);
    if (b.status == ClusterStatus::kMaybeTruncated) {
        out.status = ClusterStatus::kMaybeTruncated;
        if (out.message.empty()) out.message = b.message;
    }
    return out;
}

void validate(const SegmentationOptions& o) {
    auto fail = [](const std::string& what) {
        throw std::invalid_argument("segmentation options: " + what);
    };
    auto positive = [&](float value, const char* name) {
        if (!(value > 0.0f) || !std::isfinite(value))
            fail(std::string(name) + " must be a positive length in metres, got " +
                 std::to_string(value));
    };
    if (o.image_camera) {
        o.image_camera->validate();
        if (static_cast<std::size_t>(o.image_camera->width) * o.image_camera->height > (1u << 25))
            fail("image_camera must have at most 2^25 pixels");
    }
    positive(o.plane_distance, "plane_distance");
    positive(o.cluster_tolerance, "cluster_tolerance");
    positive(o.max_height, "max_height");
    if (!(o.hull_margin >= 0.0f && std::isfinite(o.hull_margin)))
        fail("hull_margin must be >= 0, got " + std::to_string(o.hull_margin));
    if (!(o.rim_height >= 0.0f && std::isfinite(o.rim_height)))
        fail("rim_height must be >= 0, got " + std::to_string(o.rim_height));
    if (!(o.rim_noise >= 0.0f && std::isfinite(o.rim_noise)))
        fail("rim_noise must be >= 0, got " + std::to_string(o.rim_noise));
    if (o.plane_iterations < 1)
        fail("plane_iterations must be >= 1, got " + std::to_string(o.plane_iterations));
    if (o.plane_samples < 3)
        fail("plane_samples must be >= 3, got " + std::to_string(o.plane_samples));
    if (!(o.plane_confidence > 0.0 && o.plane_confidence < 1.0))
        fail("plane_confidence must be in (0, 1), got " + std::to_string(o.plane_confidence));
    if (!(o.min_plane_fraction >= 0.0 && o.min_plane_fraction <= 1.0))
        fail("min_plane_fraction must be in [0, 1], got " + std::to_string(o.min_plane_fraction));
    if (!std::isfinite(o.min_height) || o.min_height < 0.0f || o.min_height >= o.max_height)
        fail("min_height must be >= 0 and below max_height (" + std::to_string(o.max_height) +
             "), got " + std::to_string(o.min_height));
    if (o.min_cluster_points < 1) fail("min_cluster_points must be >= 1");
    if (o.max_cluster_points < o.min_cluster_points)
        fail("max_cluster_points (" + std::to_string(o.max_cluster_points) +
             ") is below min_cluster_points (" + std::to_string(o.min_cluster_points) + ")");
    if (!o.viewpoint.allFinite()) fail("viewpoint must be finite");
    if (o.threads < 0)
        fail("threads must be >= 0 (0 = all cores), got " + std::to_string(o.threads));
    if (o.grouping != Grouping::kConvexity && o.grouping != Grouping::kEuclidean)
        fail("unknown grouping");
    SurfacePatchOptions patches = o.patches;
    patches.viewpoint = o.viewpoint;
    validate(patches);
    validate(o.convexity);
}

SegmentationResult segment_scene(const PointCloud& cloud, const SegmentationOptions& options) {
    return segment(cloud.points, cloud.width, cloud.height, options);
}

SegmentationResult segment_scene(std::span<const Eigen::Vector3f> points,
                                 const SegmentationOptions& options) {
    return segment(points, static_cast<std::uint32_t>(points.size()), 1, options);
}

std::optional<PointCloud> depth_image_of(std::span<const Eigen::Vector3f> points,
                                         const CameraIntrinsics& camera,
                                         std::vector<std::uint32_t>* source_out) {
    camera.validate();
    std::vector<std::uint32_t> own;
    std::vector<std::uint32_t>& source = source_out ? *source_out : own;
    constexpr double kTolerance = 0.01;  // pixels
    const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
    source.assign(pixels, kNoPoint);
    std::size_t finite = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector3f& p = points[i];
        if (!p.allFinite()) continue;
        if (!(p.z() > 0.0f)) return std::nullopt;
        const double u = camera.fx * p.x() / p.z() + camera.cx;
        const double v = camera.fy * p.y() / p.z() + camera.cy;
        const double column = std::round(u), row = std::round(v);
        if (!(std::abs(u - column) <= kTolerance && std::abs(v - row) <= kTolerance) ||
            column < 0.0 || row < 0.0 || column >= camera.width || row >= camera.height)
            return std::nullopt;
        const std::size_t pixel =
            static_cast<std::size_t>(row) * camera.width + static_cast<std::size_t>(column);
        if (source[pixel] != kNoPoint) return std::nullopt;
        source[pixel] = static_cast<std::uint32_t>(i);
        ++finite;
    }
    if (finite < 3) return std::nullopt;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    PointCloud image;
    image.points.assign(pixels, Eigen::Vector3f(nan, nan, nan));
    image.width = static_cast<std::uint32_t>(camera.width);
    image.height = static_cast<std::uint32_t>(camera.height);
    for (std::size_t pixel = 0; pixel < pixels; ++pixel)
        if (source[pixel] != kNoPoint) image.points[pixel] = points[source[pixel]];
    return image;
}

}  // namespace esf
