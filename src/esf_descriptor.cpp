#include "esf/esf_descriptor.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "esf/glibc_random.hpp"
#include "esf/parallel.hpp"
#include "esf_trace.hpp"

namespace esf {

using detail::kGridSide;
using detail::pack_cell;

namespace {

constexpr int kTopBin = kEsfBins - 1;       // 63
constexpr float kMinHeronProduct = 0.001f;  // s(s-a)(s-b)(s-c) in grid units (squared area)
// Line and triangle classes of the reference: a line is IN when at most one of its cells is
// empty, OUT when at most 7 are occupied; a triangle is OUT when its three lines hold at most 21
// occupied cells, IN when at most 3 of their cells are empty.
constexpr int kLineOutMaxOccupied = 7;
constexpr int kTriangleOutMaxOccupied = 21;
constexpr int kTriangleInMaxEmpty = 3;

/// PCL's pcl_round(float) for a histogram position x >= 0: floor(x + 0.5f) in float (not
/// round(): 0.49999997f gives 1). Truncation is floor for x + 0.5f > 0, and avoids the libm call
/// floor() is without SSE4.1.
inline int round_bin(float x) {
    assert(x >= 0.0f);
    return static_cast<int>(x + 0.5f);
}

/// SplitMix64, to seed xoshiro256** from one 64-bit seed.
inline std::uint64_t splitmix64(std::uint64_t& state) {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/// xoshiro256** (Blackman & Vigna): small state, fast, passes BigCrush.
class Xoshiro256 {
  public:
    explicit Xoshiro256(std::uint64_t seed) {
        for (auto& word : state_) word = splitmix64(seed);
    }
    std::uint64_t operator()() {
        const std::uint64_t result = rotl(state_[1] * 5, 7) * 9;
        const std::uint64_t t = state_[1] << 17;
        state_[2] ^= state_[0];
        state_[3] ^= state_[1];
        state_[1] ^= state_[2];
        state_[0] ^= state_[3];
        state_[2] ^= t;
        state_[3] = rotl(state_[3], 45);
        return result;
    }

  private:
    static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    std::uint64_t state_[4];
};

/// Uniform index in [0, n) from 32 random bits (Lemire's multiply-shift).
inline std::uint32_t bounded(std::uint32_t bits, std::uint32_t n) {
    return static_cast<std::uint32_t>((std::uint64_t{bits} * n) >> 32);
}

/// Angle bin of the reference, round(acos(c) / (pi/2) * 63) with PCL's float arithmetic, as a
/// table lookup: the bin only decreases as c grows, so 63 float thresholds give it exactly.
class AngleBins {
  public:
    AngleBins() {
        for (int bin = 0; bin < kTopBin; ++bin) {
            // Smallest float c in [0, 1] whose bin is <= bin.
            float lo = 0.0f, hi = 1.0f;
            while (std::nextafter(lo, 2.0f) < hi) {
                const float mid = lo + (hi - lo) * 0.5f;
                const float m = (mid == lo || mid == hi) ? std::nextafter(lo, 2.0f) : mid;
                (reference(m) <= bin ? hi : lo) = m;
            }
            threshold_[static_cast<std::size_t>(bin)] = reference(lo) <= bin ? lo : hi;
        }
        threshold_[kTopBin] = -1.0f;  // sentinel: no bin above the last
        for (int i = 0; i <= kLut; ++i) {
            const float c = static_cast<float>(i) / kLut;
            lut_[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(count_above(c));
        }
    }
    static int reference(float c) {
        const float pih = static_cast<float>(std::numbers::pi) / 2.0f;
        return round_bin(std::acos(c) / pih * static_cast<float>(kTopBin));
    }
    /// c = |cos| in [0, 1]; returns kEsfBins for NaN.
    int operator()(float c) const {
        if (!(c >= 0.0f && c <= 1.0f)) return kEsfBins;
        // bin(c) = number of thresholds above c. The table gives it at the upper edge of c's
        // bucket; buckets (1/4096) are narrower than the closest thresholds (6.2e-4 apart), so at
        // most one more threshold lies between c and that edge.
        const int bin = lut_[static_cast<std::size_t>(c * kLut) + 1];
        return bin + static_cast<int>(c < threshold_[static_cast<std::size_t>(bin)]);
    }

  private:
    int count_above(float c) const {
        int n = 0;
        while (n < kTopBin && c < threshold_[static_cast<std::size_t>(n)]) ++n;
        return n;
    }
    static constexpr int kLut = 4096;
    std::array<float, kEsfBins> threshold_{};
    std::array<std::uint8_t, kLut + 2> lut_{};
};

/// Ratio bin round(o / n * 63) of a MIXED line with o of n cells occupied, with the
/// reference's float arithmetic, tabulated for every (o, n) a 64^3 grid allows.
class RatioBins {
  public:
    RatioBins() {
        for (int n = 1; n < kGridSide; ++n)
            for (int o = 0; o <= n; ++o) {
                const float ratio = static_cast<float>(o) / static_cast<float>(n);
                table_[static_cast<std::size_t>(n * kGridSide + o)] =
                    static_cast<std::uint8_t>(round_bin(ratio * static_cast<float>(kTopBin)));
            }
    }
    int operator()(int occupied, int visited) const {
        return table_[static_cast<std::size_t>(visited * kGridSide + occupied)];
    }

  private:
    std::array<std::uint8_t, kGridSide * kGridSide> table_{};
};

const RatioBins& ratio_bin_table() {
    static const RatioBins bins;  // immutable table, built once
    return bins;
}

const AngleBins& angle_bins() {
    static const AngleBins bins;  // immutable table, built once
    return bins;
}

struct Triangle {
    std::array<std::uint8_t, 3> angle_bin;  // at p1 (between p1p2, p1p3), p3, p2
    std::array<float, 3> d2;                // |p1p2|, |p1p3|, |p2p3|
    float d3;                               // sqrt(area)
};

/// Cell index of a scaled coordinate (reference: floor(v) + h if v < 0, else ceil(v) + h - 1),
/// clamped to the grid (the reference reads outside it when rounding puts a point at 32.00001).
/// |v| <= 32, so floor and ceil come from truncation.
inline std::uint32_t cell_of(float v, int half) {
    const int truncated = static_cast<int>(v);
    const bool fractional = static_cast<float>(truncated) != v;
    const int c = v < 0.0f ? truncated - fractional + half : truncated + fractional + half - 1;
    return static_cast<std::uint32_t>(std::clamp(c, 0, 2 * half - 1));
}

}  // namespace

struct EsfEstimator::Workspace {
    detail::VoxelGrid grid;
    Points scaled;
    std::vector<std::uint32_t> cells;
    std::vector<Triangle> triangles;
    std::vector<std::uint32_t> line_start, line_end;
    std::vector<std::uint16_t> occupied;
    std::vector<std::uint8_t> visited;
    detail::TraceScratch trace;
};

const std::array<const char*, kEsfBlocks>& esf_block_names() {
    static constexpr std::array<const char*, kEsfBlocks> names = {
        "a3_in",    "a3_out", "a3_mixed", "d3_in",    "d3_out",
        "d3_mixed", "d2_in",  "d2_out",   "d2_mixed", "d2_ratio"};
    return names;
}

EsfSampler parse_esf_sampler(const std::string& name) {
    if (name == "fast") return EsfSampler::kFast;
    if (name == "pcl") return EsfSampler::kPcl;
    throw std::invalid_argument("unknown ESF sampler '" + name + "' (expected fast or pcl)");
}

const char* to_string(EsfSampler sampler) { return sampler == EsfSampler::kPcl ? "pcl" : "fast"; }

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

/// Centres the points and scales them so that the farthest lies at radius `half` (Sec. III-A:
/// translation and scale invariance). Returns false when all points coincide.
bool normalise_fast(std::span<const Eigen::Vector3f> in, int half, Points& out) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const auto& p : in) centroid += p.cast<double>();
    centroid /= static_cast<double>(in.size());
    double radius2 = 0.0;
    for (const auto& p : in)
        radius2 = std::max(radius2, (p.cast<double>() - centroid).squaredNorm());
    if (!(radius2 > 0.0) || !std::isfinite(radius2)) return false;
    const double scale = half / std::sqrt(radius2);
    out.resize(in.size());
    for (std::size_t i = 0; i < in.size(); ++i)
        out[i] = ((in[i].cast<double>() - centroid) * scale).cast<float>();
    return true;
}

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

/// One triple, with the reference's exact float operations. False when it is rejected.
inline bool triangle_pcl(const Eigen::Vector3f& p1, const Eigen::Vector3f& p2,
                         const Eigen::Vector3f& p3, Triangle& t) {
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
    for (int k = 0; k < 3; ++k) {
        const float x = std::acos(std::abs(cosines[k])) / pih * static_cast<float>(kTopBin);
        if (!(x >= 0.0f && x + 0.5f < static_cast<float>(kEsfBins))) return false;  // NaN too
        t.angle_bin[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(round_bin(x));
    }
    const auto distance = [](const Eigen::Vector3f& from, const Eigen::Vector3f& to) {
        const float dx = to.x() - from.x(), dy = to.y() - from.y(), dz = to.z() - from.z();
        return std::sqrt(dx * dx + dy * dy + dz * dz);
    };
    t.d2 = {distance(p1, p2), distance(p1, p3), distance(p2, p3)};
    t.d3 = std::sqrt(std::sqrt(heron));
    return true;
}

/// One triple, the same quantities computed directly (cosines without normalising vectors,
/// angle bins from a table). False when it is rejected.
inline bool triangle_fast(const Eigen::Vector3f& p1, const Eigen::Vector3f& p2,
                          const Eigen::Vector3f& p3, const AngleBins& bins, Triangle& t) {
    const Eigen::Vector3f v21 = p2 - p1, v31 = p3 - p1, v23 = p2 - p3;
    const float a = v21.norm(), b = v31.norm(), c = v23.norm();
    const float s = (a + b + c) * 0.5f;
    const float heron = s * (s - a) * (s - b) * (s - c);
    if (!(heron > kMinHeronProduct)) return false;
    const int t1 = bins(std::abs(v21.dot(v31)) / (a * b));
    const int t2 = bins(std::abs(v23.dot(v31)) / (c * b));
    const int t3 = bins(std::abs(v23.dot(v21)) / (c * a));
    if ((t1 | t2 | t3) >= kEsfBins) return false;
    t.angle_bin = {static_cast<std::uint8_t>(t1), static_cast<std::uint8_t>(t2),
                   static_cast<std::uint8_t>(t3)};
    t.d2 = {a, b, c};
    t.d3 = std::sqrt(std::sqrt(heron));
    return true;
}

/// True when the points lie on one line up to float rounding: the second principal axis is
/// shorter than 1e-5 of the first. Heron's formula in float does not reject such triples (its
/// cancellation error exceeds the area threshold), so they are caught here.
bool collinear(std::span<const Eigen::Vector3f> points) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : points) mean += p.cast<double>();
    mean /= static_cast<double>(points.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const auto& p : points) {
        const Eigen::Vector3d q = p.cast<double>() - mean;
        covariance += q * q.transpose();
    }
    const Eigen::Vector3d eigenvalues =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly)
            .eigenvalues();  // ascending
    return eigenvalues[1] <= 1e-10 * eigenvalues[2];
}

[[noreturn]] void throw_degenerate(std::size_t points, std::size_t accepted, std::size_t attempts) {
    std::ostringstream msg;
    msg << "degenerate cloud: only " << accepted << " non-degenerate triangles in " << attempts
        << " random triples of " << points << " points (all points on a line?)";
    throw std::invalid_argument(msg.str());
}

}  // namespace

EsfResult EsfEstimator::compute(std::span<const Eigen::Vector3f> input) {
    Workspace& ws = *workspace_;
    const EsfOptions& opt = options_;
    EsfResult result;

    FinitePoints finite;
    std::span<const Eigen::Vector3f> points = input;
    const bool all_finite = std::all_of(input.begin(), input.end(),
                                        [](const Eigen::Vector3f& p) { return p.allFinite(); });
    if (!all_finite) {
        finite = drop_non_finite(input);
        points = finite.points;
        result.dropped_points = finite.dropped;
    }
    result.points = points.size();
    if (points.size() < 3)
        throw std::invalid_argument(
            "ESF needs at least 3 finite points, got " + std::to_string(points.size()) +
            (result.dropped_points
                 ? " (" + std::to_string(result.dropped_points) + " non-finite dropped)"
                 : std::string()));
    if (points.size() > std::numeric_limits<std::int32_t>::max())
        throw std::invalid_argument("ESF input too large: " + std::to_string(points.size()) +
                                    " points");

    const int half = opt.grid_size / 2;
    const bool pcl = opt.sampler == EsfSampler::kPcl;
    if (!(pcl ? normalise_pcl(points, ws.scaled) : normalise_fast(points, half, ws.scaled)))
        throw std::invalid_argument("degenerate cloud: all " + std::to_string(points.size()) +
                                    " points are identical");

    if (collinear(points))
        throw std::invalid_argument("degenerate cloud: all " + std::to_string(points.size()) +
                                    " points lie on one line");

    // Voxel grid with one-cell dilation (Sec. III-B).
    const std::size_t n = ws.scaled.size();
    ws.cells.resize(n);
    ws.grid.clear();
    for (std::size_t i = 0; i < n; ++i) {
        const auto& p = ws.scaled[i];
        ws.cells[i] = pack_cell(cell_of(p.x(), half), cell_of(p.y(), half), cell_of(p.z(), half));
        ws.grid.set(ws.cells[i]);
    }
    ws.grid.dilate(opt.grid_size);

    // Random triples (Sec. III-C): 20,000 accepted, degenerate ones redrawn.
    const auto samples = static_cast<std::size_t>(opt.samples);
    const std::size_t max_attempts =
        samples * static_cast<std::size_t>(opt.max_attempts_per_sample);
    ws.triangles.resize(samples);
    ws.line_start.resize(3 * samples);
    ws.line_end.resize(3 * samples);
    std::size_t accepted = 0, attempts = 0;
    const auto record = [&](std::size_t i1, std::size_t i2, std::size_t i3) {
        const std::uint32_t c1 = ws.cells[i1], c2 = ws.cells[i2], c3 = ws.cells[i3];
        ws.line_start[3 * accepted] = c1, ws.line_end[3 * accepted] = c2;
        ws.line_start[3 * accepted + 1] = c1, ws.line_end[3 * accepted + 1] = c3;
        ws.line_start[3 * accepted + 2] = c2, ws.line_end[3 * accepted + 2] = c3;
        ++accepted;
    };
    if (pcl) {
        GlibcRandom random(static_cast<std::uint32_t>(opt.seed));
        while (accepted < samples) {
            if (++attempts > max_attempts) throw_degenerate(n, accepted, max_attempts);
            const std::size_t i1 = static_cast<std::size_t>(random()) % n;
            const std::size_t i2 = static_cast<std::size_t>(random()) % n;
            const std::size_t i3 = static_cast<std::size_t>(random()) % n;
            if (i1 == i2 || i1 == i3 || i2 == i3) continue;
            if (!triangle_pcl(ws.scaled[i1], ws.scaled[i2], ws.scaled[i3], ws.triangles[accepted]))
                continue;
            record(i1, i2, i3);
        }
    } else {
        const AngleBins& bins = angle_bins();
        Xoshiro256 random(opt.seed);
        const auto count = static_cast<std::uint32_t>(n);
        while (accepted < samples) {
            if (++attempts > max_attempts) throw_degenerate(n, accepted, max_attempts);
            const std::uint64_t r1 = random(), r2 = random();
            const std::uint32_t i1 = bounded(static_cast<std::uint32_t>(r1 >> 32), count);
            const std::uint32_t i2 = bounded(static_cast<std::uint32_t>(r1), count);
            const std::uint32_t i3 = bounded(static_cast<std::uint32_t>(r2 >> 32), count);
            if (i1 == i2 || i1 == i3 || i2 == i3) continue;
            if (!triangle_fast(ws.scaled[i1], ws.scaled[i2], ws.scaled[i3], bins,
                               ws.triangles[accepted]))
                continue;
            record(i1, i2, i3);
        }
    }
    result.attempts = attempts;

    // Occupancy along the three lines of every triangle (3-D Bresenham).
    ws.occupied.resize(3 * samples);
    ws.visited.resize(3 * samples);
    detail::trace_lines(ws.grid, ws.line_start, ws.line_end, ws.occupied, ws.visited, ws.trace);

    // Histograms, counted in integers: every value the reference accumulates in float is a
    // multiple of 1/32 far below 2^24 / 32, so integer sums converted at the end are identical.
    enum Block {
        kA3In,
        kA3Out,
        kA3Mixed,
        kD3In,
        kD3Out,
        kD3Mixed,
        kD2In,
        kD2Out,
        kD2Mixed,
        kRatio
    };
    std::uint32_t h[kEsfBlocks][kEsfBins] = {};
    float maxd2 = 0.0f, maxd3 = 0.0f;
    for (const Triangle& tri : ws.triangles) {
        maxd2 = std::max({maxd2, tri.d2[0], tri.d2[1], tri.d2[2]});
        maxd3 = std::max(maxd3, tri.d3);
    }
    // The reference divides by the maximum; the fast sampler multiplies by its reciprocal (a
    // last-bit difference at a bin border, far below the sampling noise).
    const float d2_scale = static_cast<float>(kTopBin) / maxd2;
    const float d3_scale = static_cast<float>(kTopBin) / maxd3;
    const auto d2_bin = [&](float d) {
        return std::min(round_bin(pcl ? d / maxd2 * static_cast<float>(kTopBin) : d * d2_scale),
                        kTopBin);
    };
    const auto d3_bin = [&](float d) {
        return std::min(round_bin(pcl ? d / maxd3 * static_cast<float>(kTopBin) : d * d3_scale),
                        kTopBin);
    };
    const RatioBins& ratio_bins = ratio_bin_table();
    for (std::size_t t = 0; t < samples; ++t) {
        const Triangle& tri = ws.triangles[t];
        const std::uint16_t* o = &ws.occupied[3 * t];
        const std::uint8_t* v = &ws.visited[3 * t];
        for (std::size_t k = 0; k < 3; ++k) {
            // Line class: IN when at most one visited cell is empty, else OUT when at most 7 are
            // occupied, else MIXED, which also counts its occupied share in the ratio histogram.
            const int in = o[k] + 1 >= v[k];
            const int out = (1 - in) & static_cast<int>(o[k] <= kLineOutMaxOccupied);
            const int mixed = 1 - in - out;
            h[kRatio][ratio_bins(o[k], v[k])] += static_cast<std::uint32_t>(mixed);
            h[kD2In + out + 2 * mixed][d2_bin(tri.d2[k])]++;
        }
        const int occupied_sum = o[0] + o[1] + o[2], visited_sum = v[0] + v[1] + v[2];
        const int out = occupied_sum <= kTriangleOutMaxOccupied;
        const int in =
            (1 - out) & static_cast<int>(visited_sum - occupied_sum <= kTriangleInMaxEmpty);
        const int cls = out + 2 * (1 - out - in);  // 0 in, 1 out, 2 mixed
        // A3: each angle weighted by the visited cells of the line opposite to it.
        std::uint32_t* a3 = h[kA3In + cls];
        a3[tri.angle_bin[0]] += v[2];
        a3[tri.angle_bin[1]] += v[0];
        a3[tri.angle_bin[2]] += v[1];
        h[kD3In + cls][d3_bin(tri.d3)]++;
    }

    // Block weights of the reference, then L1 normalisation (float, in output order).
    static constexpr float kWeights[kEsfBlocks] = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f,
                                                   1.0f, 0.5f, 2.0f, 2.0f, 1.0f};
    float sum = 0.0f;
    for (int b = 0; b < kEsfBlocks; ++b)
        for (int i = 0; i < kEsfBins; ++i) {
            const float count =
                b <= kA3Mixed ? static_cast<float>(h[b][i]) / 32.0f : static_cast<float>(h[b][i]);
            const float value = count * kWeights[b];
            result.descriptor[static_cast<std::size_t>(b * kEsfBins + i)] = value;
            sum += value;
        }
    for (float& value : result.descriptor) value /= sum;
    return result;
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
