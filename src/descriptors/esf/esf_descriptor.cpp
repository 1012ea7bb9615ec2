#include "esf/descriptors/esf/esf_descriptor.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "core/elapsed_time.hpp"
#include "descriptors/esf/esf_points.hpp"
#include "descriptors/esf/esf_trace.hpp"
#include "descriptors/esf/esf_triangles.hpp"
#include "esf/core/parallel.hpp"
#include "esf/descriptors/esf/glibc_random.hpp"

namespace esf {

using detail::cell_of;
using detail::kGridSide;
using detail::kTopBin;
using detail::pack_cell;
using detail::round_bin;

namespace {

constexpr float kMinHeronProduct = 0.001f;  // s(s-a)(s-b)(s-c) in grid units (squared area)

}  // namespace

struct EsfEstimator::Workspace {
    detail::VoxelGrid grid;
    Points scaled;
    Points finite;                            // the finite input points, when some are not
    std::vector<std::uint32_t> cells;         // pcl sampler: cell of each point
    std::vector<detail::PackedPoint> packed;  // fast sampler: points with their cells
    detail::TriangleSet triangles;
    std::vector<std::uint32_t> occupied;
    std::vector<std::uint8_t> visited;
    detail::TraceScratch trace;
    detail::TraceKernelTrials trials;  // Kernels::kBest: which tracer is fastest here
};

const std::array<const char*, kEsfBlocks>& esf_block_names() {
    static constexpr std::array<const char*, kEsfBlocks> names = {
        "a3_in",    "a3_out", "a3_mixed", "d3_in",    "d3_out",
        "d3_mixed", "d2_in",  "d2_out",   "d2_mixed", "d2_ratio"};
    return names;
}

EsfEstimator::EsfEstimator(const EsfOptions& options)
    : options_(options), workspace_(std::make_unique<Workspace>()) {
    if (options.samples < 1 || options.samples > 10'000'000)
        throw std::invalid_argument("ESF samples must be in [1, 10000000], got " +
                                    std::to_string(options.samples));
    if (options.grid_size < 8 || options.grid_size > kGridSide || options.grid_size % 2 != 0)
        throw std::invalid_argument("ESF grid size must be even and in [8, 64], got " +
                                    std::to_string(options.grid_size));
    if (options.sampler == EsfSampler::kPcl && options.grid_size != 64)
        throw std::invalid_argument("the pcl sampler reproduces PCL's fixed 64^3 grid; got grid " +
                                    std::to_string(options.grid_size));
    if (options.max_attempts_per_sample < 1)
        throw std::invalid_argument("max_attempts_per_sample must be at least 1");
}

EsfEstimator::~EsfEstimator() = default;
EsfEstimator::EsfEstimator(EsfEstimator&&) noexcept = default;
EsfEstimator& EsfEstimator::operator=(EsfEstimator&&) noexcept = default;

namespace {

/// The reference's float arithmetic (compute3DCentroid, demeanPointCloud, scale 1/R * 32).
bool normalise_pcl(std::span<const Eigen::Vector3f> in, Points& out) {
    float sum[3] = {0.0f, 0.0f, 0.0f};
    for (const auto& p : in)
        for (int k = 0; k < 3; ++k) sum[k] += p[k];
    const float n = static_cast<float>(in.size());
    out.resize(in.size());
    float max_distance = 0.0f;
    for (std::size_t i = 0; i < in.size(); ++i) {
        for (int k = 0; k < 3; ++k) out[i][k] = in[i][k] - sum[k] / n;
        const float d =
            std::sqrt(out[i].x() * out[i].x() + out[i].y() * out[i].y() + out[i].z() * out[i].z());
        if (d > max_distance) max_distance = d;
    }
    if (!(max_distance > 0.0f) || !std::isfinite(max_distance)) return false;
    const float scale = 1.0f / max_distance * 32.0f;
    for (auto& p : out) p *= scale;
    return true;
}

/// Eigen's SSE reduction order for a 4-float packet (w = 0): (x + z) + y.
inline float sum_sse_order(float x, float y, float z) { return (x + z) + y; }

/// One triple, with the reference's exact float operations, stored as triangle `at` of the set.
/// False when it is rejected.
inline bool triangle_pcl(const Eigen::Vector3f& p1, const Eigen::Vector3f& p2,
                         const Eigen::Vector3f& p3, std::size_t at, detail::TriangleSet& set) {
    const Eigen::Vector3f v21 = p2 - p1, v31 = p3 - p1, v23 = p2 - p3;
    const float a =
        std::sqrt(sum_sse_order(v21.x() * v21.x(), v21.y() * v21.y(), v21.z() * v21.z()));
    const float b =
        std::sqrt(sum_sse_order(v31.x() * v31.x(), v31.y() * v31.y(), v31.z() * v31.z()));
    const float c =
        std::sqrt(sum_sse_order(v23.x() * v23.x(), v23.y() * v23.y(), v23.z() * v23.z()));
    const float s = (a + b + c) * 0.5f;
    const float heron = s * (s - a) * (s - b) * (s - c);
    if (heron <= kMinHeronProduct) return false;
    const Eigen::Vector3f n21 = v21 / a, n31 = v31 / b, n23 = v23 / c;
    const auto dot = [](const Eigen::Vector3f& u, const Eigen::Vector3f& v) {
        return sum_sse_order(u.x() * v.x(), u.y() * v.y(), u.z() * v.z());
    };
    const float pih = static_cast<float>(std::numbers::pi) / 2.0f;
    const float cosines[3] = {dot(n21, n31), dot(n23, n31), dot(n23, n21)};
    std::uint32_t bins = 0;
    for (int k = 0; k < 3; ++k) {
        const float x = std::acos(std::abs(cosines[k])) / pih * static_cast<float>(kTopBin);
        if (!(x >= 0.0f && x + 0.5f < static_cast<float>(kEsfBins))) return false;  // NaN too
        bins |= static_cast<std::uint32_t>(round_bin(x)) << (8 * k);
    }
    const auto distance = [](const Eigen::Vector3f& from, const Eigen::Vector3f& to) {
        const float dx = to.x() - from.x(), dy = to.y() - from.y(), dz = to.z() - from.z();
        return std::sqrt(dx * dx + dy * dy + dz * dz);
    };
    const std::size_t n = set.samples;
    set.angle_bins[at] = bins;
    set.d2[at] = distance(p1, p2);
    set.d2[n + at] = distance(p1, p3);
    set.d2[2 * n + at] = distance(p2, p3);
    set.d3[at] = std::sqrt(std::sqrt(heron));
    set.max_d2 = std::max({set.max_d2, set.d2[at], set.d2[n + at], set.d2[2 * n + at]});
    set.max_d3 = std::max(set.max_d3, set.d3[at]);
    return true;
}

/// True when the points lie on one line up to float rounding: the second principal axis is
/// shorter than 1e-5 of the first. Heron's formula in float does not reject such triples (its
/// cancellation error exceeds the area threshold), so they are caught here.
bool collinear(std::span<const Eigen::Vector3f> points) {
    // Scalar accumulators (an Eigen matrix accumulator goes through memory on every point).
    double mx = 0.0, my = 0.0, mz = 0.0;
    for (const auto& p : points) {
        mx += p.x();
        my += p.y();
        mz += p.z();
    }
    const double count = static_cast<double>(points.size());
    mx /= count;
    my /= count;
    mz /= count;
    double xx = 0.0, xy = 0.0, xz = 0.0, yy = 0.0, yz = 0.0, zz = 0.0;
    for (const auto& p : points) {
        const double x = p.x() - mx, y = p.y() - my, z = p.z() - mz;
        xx += x * x;
        xy += x * y;
        xz += x * z;
        yy += y * y;
        yz += y * z;
        zz += z * z;
    }
    Eigen::Matrix3d covariance;
    covariance << xx, xy, xz, xy, yy, yz, xz, yz, zz;
    return detail::on_one_line(covariance);
}

[[noreturn]] void throw_degenerate(std::size_t points, std::size_t accepted, std::size_t attempts) {
    std::ostringstream msg;
    msg << "degenerate cloud: only " << accepted << " non-degenerate triangles in " << attempts
        << " random triples of " << points << " points (all points on a line?)";
    throw std::invalid_argument(msg.str());
}

}  // namespace

void require_esf_points(std::size_t finite, std::size_t dropped) {
    if (finite >= 3) return;
    throw std::invalid_argument(
        "ESF needs at least 3 finite points, got " + std::to_string(finite) +
        (dropped ? " (" + std::to_string(dropped) + " non-finite dropped)" : std::string()));
}

EsfResult EsfEstimator::compute(std::span<const Eigen::Vector3f> input) {
    Workspace& ws = *workspace_;
    const EsfOptions& opt = options_;
    EsfResult result;

    const int half = opt.grid_size / 2;
    const bool pcl = opt.sampler == EsfSampler::kPcl;
    const detail::SimdLevel simd = detail::simd_level(opt.kernels);
    // The fast sampler's centring pass reveals non-finite points for free; the pcl sampler
    // checks every point first.
    using detail::NormaliseOutcome;
    detail::Normalisation normalisation;
    NormaliseOutcome normalised = NormaliseOutcome::kNonFinite;
    if (!pcl && input.size() >= 3)
        normalised = detail::normalise_points(input, half, simd, normalisation);
    std::span<const Eigen::Vector3f> points = input;
    const bool all_finite =
        !pcl && input.size() >= 3
            ? normalised != NormaliseOutcome::kNonFinite
            : std::all_of(input.begin(), input.end(),
                          [](const Eigen::Vector3f& p) { return p.allFinite(); });
    if (!all_finite) {
        result.dropped_points = detail::keep_finite_points(input, simd, ws.finite);
        points = ws.finite;
        if (!pcl && points.size() >= 3)
            normalised = detail::normalise_points(points, half, simd, normalisation);
    }
    result.points = points.size();
    require_esf_points(points.size(), result.dropped_points);
    if (points.size() > std::numeric_limits<std::int32_t>::max())
        throw std::invalid_argument("ESF input too large: " + std::to_string(points.size()) +
                                    " points");

    const auto identical = [&] {
        return std::invalid_argument("degenerate cloud: all " + std::to_string(points.size()) +
                                     " points are identical");
    };
    const auto on_one_line = [&] {
        return std::invalid_argument("degenerate cloud: all " + std::to_string(points.size()) +
                                     " points lie on one line");
    };
    if (pcl) {
        if (!normalise_pcl(points, ws.scaled)) throw identical();
        if (collinear(points)) throw on_one_line();
    } else if (normalised != NormaliseOutcome::kNormalised) {
        throw identical();
    }

    // Voxel grid with one-cell dilation (Sec. III-B).
    const std::size_t n = points.size();
    ws.grid.clear();
    if (pcl) {
        ws.cells.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const auto& p = ws.scaled[i];
            ws.cells[i] =
                pack_cell(cell_of(p.x(), half), cell_of(p.y(), half), cell_of(p.z(), half));
            ws.grid.set(ws.cells[i]);
        }
    } else {
        // One pass: scaled point, its cell, the grid and the moments for the collinearity test
        // (the scaled points are centred, so raw moments lose nothing).
        if (detail::voxelise_points(points, normalisation, half, simd, ws.packed, ws.cells,
                                    ws.grid))
            throw on_one_line();
    }
    ws.grid.dilate(opt.grid_size, simd);

    // Random triples (Sec. III-C): `samples` accepted, degenerate ones redrawn.
    const auto samples = static_cast<std::size_t>(opt.samples);
    const std::size_t max_attempts =
        samples * static_cast<std::size_t>(opt.max_attempts_per_sample);
    detail::TriangleSet& triangles = ws.triangles;
    triangles.resize(samples);
    std::size_t accepted = 0, attempts = 0;
    if (pcl) {
        GlibcRandom random(static_cast<std::uint32_t>(opt.seed));
        while (accepted < samples) {
            if (++attempts > max_attempts) throw_degenerate(n, accepted, max_attempts);
            const std::size_t i1 = static_cast<std::size_t>(random()) % n;
            const std::size_t i2 = static_cast<std::size_t>(random()) % n;
            const std::size_t i3 = static_cast<std::size_t>(random()) % n;
            if (i1 == i2 || i1 == i3 || i2 == i3) continue;
            if (!triangle_pcl(ws.scaled[i1], ws.scaled[i2], ws.scaled[i3], accepted, triangles))
                continue;
            const std::uint32_t c1 = ws.cells[i1], c2 = ws.cells[i2], c3 = ws.cells[i3];
            triangles.line_start[accepted] = c1, triangles.line_end[accepted] = c2;
            triangles.line_start[samples + accepted] = c1;
            triangles.line_end[samples + accepted] = c3;
            triangles.line_start[2 * samples + accepted] = c2;
            triangles.line_end[2 * samples + accepted] = c3;
            ++accepted;
        }
    } else {
        const detail::SampleCount count =
            detail::sample_triangles_fast(ws.packed.data(), static_cast<std::uint32_t>(n), opt.seed,
                                          max_attempts, kMinHeronProduct, simd, triangles);
        accepted = count.accepted;
        attempts = count.attempts;
        if (accepted < samples) throw_degenerate(n, accepted, max_attempts);
    }
    result.attempts = attempts;

    // Occupancy along the three lines of every triangle (3-D Bresenham). Every line joins two
    // point cells, set before the dilation.
    const std::size_t lines = 3 * samples;
    ws.occupied.resize(lines + 16);  // + slack for full-width SIMD reads
    ws.visited.resize(lines + 16);
    const bool trial = opt.kernels == Kernels::kBest && !ws.trials.decided();
    const Kernels kernels = trial ? ws.trials.next() : opt.kernels;
    const auto trace_start = std::chrono::steady_clock::now();
    detail::trace_lines(ws.grid, std::span(triangles.line_start).first(lines),
                        std::span(triangles.line_end).first(lines),
                        std::span(ws.occupied).first(lines), std::span(ws.visited).first(lines),
                        ws.trace, kernels, detail::LineEnds::kSetBeforeDilation);
    if (trial) {
        const double seconds = detail::seconds_since(trace_start);
        std::size_t cells = 0;
        for (std::size_t i = 0; i < lines; ++i) cells += ws.visited[i];
        ws.trials.record(kernels, seconds, cells);
    }

    // Histograms, counted in integers: every value the reference accumulates in float is a
    // multiple of 1/32 far below 2^24 / 32, so integer sums converted at the end are identical.
    const detail::EsfCounts h =
        detail::histogram_triangles(triangles, ws.occupied.data(), ws.visited.data(), pcl, simd);
    constexpr int kA3Mixed = 2;

    // Block weights of the reference, then L1 normalisation (float, in output order).
    static constexpr float kWeights[kEsfBlocks] = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f,
                                                   1.0f, 0.5f, 2.0f, 2.0f, 1.0f};
    float sum = 0.0f;
    for (int b = 0; b < kEsfBlocks; ++b)
        for (int i = 0; i < kEsfBins; ++i) {
            const auto raw =
                static_cast<float>(h[static_cast<std::size_t>(b)][static_cast<std::size_t>(i)]);
            const float count = b <= kA3Mixed ? raw / 32.0f : raw;
            const float value = count * kWeights[b];
            result.descriptor[static_cast<std::size_t>(b * kEsfBins + i)] = value;
            sum += value;
        }
    for (float& value : result.descriptor) value /= sum;
    return result;
}

EsfEstimatorPool::EsfEstimatorPool(const EsfOptions& options) : options_(options) {
    free_.push_back(std::make_unique<EsfEstimator>(options_));  // validates the options
}

EsfEstimatorPool::~EsfEstimatorPool() = default;

EsfResult EsfEstimatorPool::compute(std::span<const Eigen::Vector3f> points) const {
    std::unique_ptr<EsfEstimator> estimator;
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        if (!free_.empty()) {
            estimator = std::move(free_.back());
            free_.pop_back();
        }
    }
    if (!estimator) estimator = std::make_unique<EsfEstimator>(options_);
    struct GiveBack {  // also when compute() throws
        const EsfEstimatorPool& pool;
        std::unique_ptr<EsfEstimator>& estimator;
        ~GiveBack() {
            const std::lock_guard<std::mutex> lock(pool.mutex_);
            pool.free_.push_back(std::move(estimator));
        }
    } give_back{*this, estimator};
    return estimator->compute(points);
}

EsfResult compute_esf(std::span<const Eigen::Vector3f> points, const EsfOptions& options) {
    return EsfEstimator(options).compute(points);
}

std::vector<EsfBatchItem> compute_esf_batch(std::span<const Points> clouds,
                                            const EsfOptions& options, int threads) {
    std::vector<EsfBatchItem> items(clouds.size());
    const int slots = resolve_threads(threads);
    std::vector<EsfEstimator> estimators;
    estimators.reserve(static_cast<std::size_t>(slots));
    for (int i = 0; i < slots; ++i) estimators.emplace_back(options);
    parallel_for_slots(clouds.size(), slots, [&](std::size_t i, int slot) {
        try {
            items[i].result = estimators[static_cast<std::size_t>(slot)].compute(clouds[i]);
        } catch (const std::exception& e) {
            items[i].error = e.what();
        }
    });
    return items;
}

double l1_distance(const EsfDescriptor& a, const EsfDescriptor& b) {
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) sum += std::abs(static_cast<double>(a[i]) - b[i]);
    return sum;
}

}  // namespace esf
