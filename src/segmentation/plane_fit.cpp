#include "segmentation/plane_fit.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/splitmix64.hpp"
#include "esf/core/parallel.hpp"

namespace esf::detail {

namespace {

// RANSAC hypotheses scored between two checks of the stopping rule.
constexpr std::size_t kHypothesisBatch = 32;

// One generator per RANSAC hypothesis, seeded from (seed, hypothesis index), so results never
// depend on the scheduling.
SplitMix64 hypothesis_generator(std::uint64_t seed, std::uint64_t index) {
    return SplitMix64(seed ^ (index * 0xD1B54A32D192ED03ull + 0x8CB92BA72F3D8DD7ull));
}

using Hypothesis = PlaneHypothesis;

Hypothesis plane_hypothesis(std::span<const Eigen::Vector3f> samples, std::uint64_t seed,
                            std::size_t index, float distance) {
    SplitMix64 rng = hypothesis_generator(seed, index);
    const std::size_t m = samples.size();
    const std::size_t i0 = rng.below(m);
    std::size_t i1 = rng.below(m);
    std::size_t i2 = rng.below(m);
    for (int retry = 0; retry < 8 && (i1 == i0 || i2 == i0 || i2 == i1); ++retry) {
        if (i1 == i0) i1 = rng.below(m);
        if (i2 == i0 || i2 == i1) i2 = rng.below(m);
    }
    Hypothesis h;
    if (i1 == i0 || i2 == i0 || i2 == i1) return h;
    const Eigen::Vector3f a = samples[i0];
    const Eigen::Vector3f ab = samples[i1] - a;
    const Eigen::Vector3f ac = samples[i2] - a;
    const Eigen::Vector3f n = ab.cross(ac);
    const float n_norm = n.norm();
    // Nearly collinear samples give no plane (sine of the angle below 1e-4).
    if (!(n_norm > 1e-4f * ab.norm() * ac.norm())) return h;
    h.normal = n / n_norm;
    h.d = -h.normal.dot(a);
    std::size_t count = 0;
    const float nx = h.normal.x(), ny = h.normal.y(), nz = h.normal.z(), d = h.d;
    for (const Eigen::Vector3f& p : samples)
        count += std::abs(nx * p.x() + ny * p.y() + nz * p.z() + d) <= distance ? 1 : 0;
    h.inliers = count;
    return h;
}

}  // namespace

/// RANSAC (Fischler & Bolles 1981) with the usual adaptive stopping rule: stop after
/// log(1 - confidence) / log(1 - w^3) hypotheses, w the best inlier ratio so far.
Hypothesis ransac_plane(std::span<const Eigen::Vector3f> samples,
                        const SegmentationOptions& options) {
    Hypothesis best;
    if (samples.size() < 3) return best;
    const std::size_t max_hypotheses = static_cast<std::size_t>(options.plane_iterations);
    std::vector<Hypothesis> batch(kHypothesisBatch);
    std::size_t done = 0;
    double needed = static_cast<double>(max_hypotheses);
    while (done < max_hypotheses && static_cast<double>(done) < needed) {
        const std::size_t count = std::min(kHypothesisBatch, max_hypotheses - done);
        parallel_for(count, options.threads, [&](std::size_t i) {
            batch[i] = plane_hypothesis(samples, options.seed, done + i, options.plane_distance);
        });
        for (std::size_t i = 0; i < count; ++i)
            if (batch[i].inliers > best.inliers) best = batch[i];
        done += count;
        const double w = static_cast<double>(best.inliers) / static_cast<double>(samples.size());
        const double w3 = w * w * w;
        if (w3 >= 1.0) break;
        if (w3 > 0.0) needed = std::log(1.0 - options.plane_confidence) / std::log1p(-w3);
    }
    return best;
}

/// Least-squares plane through the points within `distance` of `plane` (normal = eigenvector
/// of the smallest eigenvalue of their covariance). Returns the input plane when fewer than 3.
Plane refit_plane(std::span<const Eigen::Vector3f> points, const Plane& plane, float distance) {
    // Centre on a point of the plane to keep the second moments well conditioned.
    const Eigen::Vector3d origin = (-plane.d * plane.normal).cast<double>();
    std::size_t count = 0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3f& p : points) {
        if (std::abs(plane.height(p)) > distance) continue;
        const Eigen::Vector3d q = p.cast<double>() - origin;
        ++count;
        sum += q;
        outer.noalias() += q * q.transpose();
    }
    if (count < 3) return plane;
    const double n = static_cast<double>(count);
    const Eigen::Vector3d mean = sum / n;
    const Eigen::Matrix3d covariance = outer / n - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    Eigen::Vector3d normal = solver.eigenvectors().col(0);
    if (!normal.allFinite() || normal.norm() < 0.5) return plane;
    normal.normalize();
    if (normal.dot(plane.normal.cast<double>()) < 0.0) normal = -normal;
    Plane refined;
    refined.normal = normal.cast<float>();
    refined.d = static_cast<float>(-normal.dot(mean + origin));
    return refined;
}

Plane facing(Plane plane, const Eigen::Vector3f& viewpoint) {
    if (plane.height(viewpoint) < 0.0f) {
        plane.normal = -plane.normal;
        plane.d = -plane.d;
    }
    return plane;
}

std::pair<Eigen::Vector3f, Eigen::Vector3f> plane_basis(const Eigen::Vector3f& normal) {
    const Eigen::Vector3f helper =
        std::abs(normal.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
    const Eigen::Vector3f u = normal.cross(helper).normalized();
    const Eigen::Vector3f w = normal.cross(u);
    return {u, w};
}

}  // namespace esf::detail
