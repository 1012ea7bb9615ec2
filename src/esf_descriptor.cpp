#include "esf/esf_descriptor.hpp"

#include <algorithm>
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

constexpr int kTopBin = kEsfBins - 1;  // 63
constexpr float kMinHeronProduct = 0.001f;  // s(s-a)(s-b)(s-c) in grid units (squared area)
// Line and triangle classes of the reference: a line is IN when at most one of its cells is
// empty, OUT when at most 7 are occupied; a triangle is OUT when its three lines hold at most 21
// occupied cells, IN when at most 3 of their cells are empty.
constexpr int kLineOutMaxOccupied = 7;
constexpr int kTriangleOutMaxOccupied = 21;
constexpr int kTriangleInMaxEmpty = 3;

enum LineClass : std::uint8_t { kIn = 0, kOut = 1, kMixed = 2 };

/// PCL's pcl_round(float): floor(x + 0.5f) for x >= 0 (not round(): 0.49999997f gives 1).
inline float pcl_round(float x) { return x < 0.0f ? std::ceil(x - 0.5f) : std::floor(x + 0.5f); }

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
        for (int i = 0; i <= kLut; ++i) {
            const float c = static_cast<float>(i) / kLut;
            lut_[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(count_above(c));
        }
    }
    static int reference(float c) {
        const float pih = static_cast<float>(std::numbers::pi) / 2.0f;
        return static_cast<int>(pcl_round(std::acos(c) / pih * static_cast<float>(kTopBin)));
    }
    /// c = |cos| in [0, 1]; returns kEsfBins for NaN.
    int operator()(float c) const {
        if (!(c >= 0.0f && c <= 1.0f)) return kEsfBins;
        // bin(c) = number of thresholds above c; the table gives it at the bucket's upper edge.
        int bin = lut_[static_cast<std::size_t>(c * kLut) + 1];
        while (bin < kTopBin && c < threshold_[static_cast<std::size_t>(bin)]) ++bin;
        return bin;
    }

private:
    int count_above(float c) const {
        int n = 0;
        while (n < kTopBin && c < threshold_[static_cast<std::size_t>(n)]) ++n;
        return n;
    }
    static constexpr int kLut = 4096;
    std::array<float, kTopBin> threshold_{};
    std::array<std::uint8_t, kLut + 2> lut_{};
};

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
inline std::uint32_t cell_of(float v, int half) {
    const float c = v < 0.0f ? std::floor(v) + static_cast<float>(half)
                             : std::ceil(v) + static_cast<float>(half - 1);
    return static_cast<std::uint32_t>(std::clamp(static_cast<int>(c), 0, 2 * half - 1));
}

}  // namespace

struct EsfEstimator::Workspace {
    detail::VoxelGrid grid;
    Points scaled;
    std::vector<std::uint32_t> cells;
    std::vector<Triangle> triangles;
    std::vector<std::uint32_t> line_start, line_end;
    std::vector<std::uint16_t> occupied;
    std::vector<std::uint8_t> classes;  // 3 line classes per sample, then 1 triangle class each
    detail::TraceScratch trace;
};

const std::array<const char*, kEsfBlocks>& esf_block_names() {
    static constexpr std::array<const char*, kEsfBlocks> names = {
        "a3_in", "a3_out", "a3_mixed", "d3_in", "d3_out", "d3_mixed",
        "d2_in", "d2_out", "d2_mixed", "d2_ratio"};
    return names;
}

EsfSampler parse_esf_sampler(const std::string& name) {
    if (name == "fast") return EsfSampler::kFast;
    if (name == "pcl") return EsfSampler::kPcl;
    throw std::invalid_argument("unknown ESF sampler '" + name + "' (expected fast or pcl)");
}

const char* to_string(EsfSampler sampler) {
    return sampler == EsfSampler::kPcl ? "pcl" : "fast";
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

/// Centres the points and scales them so that the farthest lies at radius `half` (Sec. III-A:
/// translation and scale invariance). Returns false when all points coincide.
bool normalise_fast(std::span<const Eigen::Vector3f> in, int half, Points& out) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const auto& p : in) centroid += p.cast<double>();
    centroid /= static_cast<double>(in.size());
    double radius2 = 0.0;
    for (const auto& p : in) radius2 = std::max(radius2, (p.cast<double>() - centroid).squaredNorm());
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
        const float d = std::sqrt(out[i].x() * out[i].x() + out[i].y() * out[i].y() +
                                  out[i].z() * out[i].z());
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
    const float a = std::sqrt(sum_sse_order(v21.x() * v21.x(), v21.y() * v21.y(), v21.z() * v21.z()));
    const float b = std::sqrt(sum_sse_order(v31.x() * v31.x(), v31.y() * v31.y(), v31.z() * v31.z()));
    const float c = std::sqrt(sum_sse_order(v23.x() * v23.x(), v23.y() * v23.y(), v23.z() * v23.z()));
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
        const float bin = pcl_round(std::acos(std::abs(cosines[k])) / pih * static_cast<float>(kTopBin));
        if (!(bin >= 0.0f && bin < static_cast<float>(kEsfBins))) return false;  // NaN too
        t.angle_bin[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(bin);
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
        throw std::invalid_argument("ESF needs at least 3 finite points, got " +
                                    std::to_string(points.size()) +
                                    (result.dropped_points
                                         ? " (" + std::to_string(result.dropped_points) +
                                               " non-finite dropped)"
                                         : std::string()));
    if (points.size() > std::numeric_limits<std::int32_t>::max())
        throw std::invalid_argument("ESF input too large: " + std::to_string(points.size()) +
                                    " points");

    const int half = opt.grid_size / 2;
    const bool pcl = opt.sampler == EsfSampler::kPcl;
    if (!(pcl ? normalise_pcl(points, ws.scaled) : normalise_fast(points, half, ws.scaled)))
        throw std::invalid_argument("degenerate cloud: all " + std::to_string(points.size()) +
                                    " points are identical");

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
    const std::size_t max_attempts = samples * static_cast<std::size_t>(opt.max_attempts_per_sample);
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
    detail::trace_lines(ws.grid, ws.line_start, ws.line_end, ws.occupied, ws.trace);

    // Histograms, in the reference's order of operations.
    float h[kEsfBlocks][kEsfBins] = {};
    enum Block { kA3In, kA3Out, kA3Mixed, kD3In, kD3Out, kD3Mixed, kD2In, kD2Out, kD2Mixed, kRatio };
    float maxd2 = 0.0f, maxd3 = 0.0f;
    std::vector<std::uint8_t>& classes = ws.classes;
    classes.resize(4 * samples);
    for (std::size_t t = 0; t < samples; ++t) {
        const Triangle& tri = ws.triangles[t];
        int occupied_sum = 0, visited_sum = 0;
        int visited[3];
        for (int k = 0; k < 3; ++k) {
            const std::size_t line = 3 * t + static_cast<std::size_t>(k);
            const int o = ws.occupied[line];
            const int v = static_cast<int>(detail::visited_cells(ws.line_start[line], ws.line_end[line]));
            visited[k] = v;
            occupied_sum += o;
            visited_sum += v;
            LineClass cls = kMixed;
            if (o >= v - 1) {
                cls = kIn;
            } else if (o <= kLineOutMaxOccupied) {
                cls = kOut;
            } else {
                const float ratio = static_cast<float>(o) / static_cast<float>(v);
                h[kRatio][static_cast<int>(pcl_round(ratio * static_cast<float>(kTopBin)))]++;
            }
            classes[line] = cls;
            maxd2 = std::max(maxd2, tri.d2[static_cast<std::size_t>(k)]);
        }
        maxd3 = std::max(maxd3, tri.d3);
        // A3: each angle weighted by the visited cells of the line opposite to it.
        int block = kA3Mixed;
        if (occupied_sum <= kTriangleOutMaxOccupied) {
            block = kA3Out;
        } else if (visited_sum - occupied_sum <= kTriangleInMaxEmpty) {
            block = kA3In;
        }
        h[block][tri.angle_bin[0]] += static_cast<float>(visited[2]) / 32.0f;
        h[block][tri.angle_bin[1]] += static_cast<float>(visited[0]) / 32.0f;
        h[block][tri.angle_bin[2]] += static_cast<float>(visited[1]) / 32.0f;
        classes[3 * samples + t] = static_cast<std::uint8_t>(block - kA3In);  // 0 in, 1 out, 2 mixed
    }
    for (std::size_t t = 0; t < samples; ++t) {
        const Triangle& tri = ws.triangles[t];
        const int d3_bin = static_cast<int>(pcl_round(tri.d3 / maxd3 * static_cast<float>(kTopBin)));
        if (d3_bin >= 0 && d3_bin < kEsfBins) h[kD3In + classes[3 * samples + t]][d3_bin]++;
        for (int k = 0; k < 3; ++k) {
            const std::size_t line = 3 * t + static_cast<std::size_t>(k);
            const int d2_bin = static_cast<int>(
                pcl_round(tri.d2[static_cast<std::size_t>(k)] / maxd2 * static_cast<float>(kTopBin)));
            h[kD2In + classes[line]][std::clamp(d2_bin, 0, kTopBin)]++;
        }
    }

    // Block weights of the reference, then L1 normalisation (float, in output order).
    static constexpr float kWeights[kEsfBlocks] = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f,
                                                   1.0f, 0.5f, 2.0f, 2.0f, 1.0f};
    float sum = 0.0f;
    for (int b = 0; b < kEsfBlocks; ++b)
        for (int i = 0; i < kEsfBins; ++i) {
            const float value = h[b][i] * kWeights[b];
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
