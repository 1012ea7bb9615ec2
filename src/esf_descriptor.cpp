#include "esf/esf_descriptor.hpp"

#include <immintrin.h>

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
    std::vector<float> xs, ys, zs;  // scaled, one array per axis (for gathers)
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
    double cx = 0.0, cy = 0.0, cz = 0.0;
    for (const auto& p : in) {
        cx += p.x();
        cy += p.y();
        cz += p.z();
    }
    const double count = static_cast<double>(in.size());
    cx /= count;
    cy /= count;
    cz /= count;
    double radius2 = 0.0;
    for (const auto& p : in) {
        const double x = p.x() - cx, y = p.y() - cy, z = p.z() - cz;
        radius2 = std::max(radius2, x * x + y * y + z * z);
    }
    if (!(radius2 > 0.0) || !std::isfinite(radius2)) return false;
    const double scale = half / std::sqrt(radius2);
    out.resize(in.size());
    for (std::size_t i = 0; i < in.size(); ++i)
        out[i] = Eigen::Vector3f(static_cast<float>((in[i].x() - cx) * scale),
                                 static_cast<float>((in[i].y() - cy) * scale),
                                 static_cast<float>((in[i].z() - cz) * scale));
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

/// The per-triple quantities of the fast sampler before binning, in the exact float operations
/// that both the scalar and the SIMD path perform (no fused multiply-add), so that both accept
/// the same triples and give the same values.
struct TripleGeometry {
    float a, b, c;           // |p1p2|, |p1p3|, |p2p3|
    float cos1, cos2, cos3;  // |cos| at p1, p3, p2
    float heron;             // s(s-a)(s-b)(s-c)
};

inline TripleGeometry triple_geometry(const float* xs, const float* ys, const float* zs,
                                      std::uint32_t i1, std::uint32_t i2, std::uint32_t i3) {
    const float x21 = xs[i2] - xs[i1], y21 = ys[i2] - ys[i1], z21 = zs[i2] - zs[i1];
    const float x31 = xs[i3] - xs[i1], y31 = ys[i3] - ys[i1], z31 = zs[i3] - zs[i1];
    const float x23 = xs[i2] - xs[i3], y23 = ys[i2] - ys[i3], z23 = zs[i2] - zs[i3];
    TripleGeometry g;
    g.a = std::sqrt(x21 * x21 + y21 * y21 + z21 * z21);
    g.b = std::sqrt(x31 * x31 + y31 * y31 + z31 * z31);
    g.c = std::sqrt(x23 * x23 + y23 * y23 + z23 * z23);
    g.cos1 = std::abs(x21 * x31 + y21 * y31 + z21 * z31) / (g.a * g.b);
    g.cos2 = std::abs(x23 * x31 + y23 * y31 + z23 * z31) / (g.c * g.b);
    g.cos3 = std::abs(x23 * x21 + y23 * y21 + z23 * z21) / (g.c * g.a);
    const float s = (g.a + g.b + g.c) * 0.5f;
    g.heron = s * (s - g.a) * (s - g.b) * (s - g.c);
    return g;
}

#define ESF_TARGET_AVX2 __attribute__((target("avx2")))

ESF_TARGET_AVX2 inline __m256 dot_x8(__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by,
                                     __m256 bz) {
    return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(ay, by)),
                         _mm256_mul_ps(az, bz));
}

/// Eight triples at once (AVX2): the same operations as triple_geometry, lane by lane.
ESF_TARGET_AVX2 void triple_geometry_x8(const float* xs, const float* ys, const float* zs,
                                        const std::uint32_t* i1, const std::uint32_t* i2,
                                        const std::uint32_t* i3, TripleGeometry* out) {
    const __m256i j1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(i1));
    const __m256i j2 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(i2));
    const __m256i j3 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(i3));
    const __m256 x1 = _mm256_i32gather_ps(xs, j1, 4), y1 = _mm256_i32gather_ps(ys, j1, 4),
                 z1 = _mm256_i32gather_ps(zs, j1, 4);
    const __m256 x2 = _mm256_i32gather_ps(xs, j2, 4), y2 = _mm256_i32gather_ps(ys, j2, 4),
                 z2 = _mm256_i32gather_ps(zs, j2, 4);
    const __m256 x3 = _mm256_i32gather_ps(xs, j3, 4), y3 = _mm256_i32gather_ps(ys, j3, 4),
                 z3 = _mm256_i32gather_ps(zs, j3, 4);
    const __m256 x21 = _mm256_sub_ps(x2, x1), y21 = _mm256_sub_ps(y2, y1),
                 z21 = _mm256_sub_ps(z2, z1);
    const __m256 x31 = _mm256_sub_ps(x3, x1), y31 = _mm256_sub_ps(y3, y1),
                 z31 = _mm256_sub_ps(z3, z1);
    const __m256 x23 = _mm256_sub_ps(x2, x3), y23 = _mm256_sub_ps(y2, y3),
                 z23 = _mm256_sub_ps(z2, z3);
    const __m256 sign = _mm256_set1_ps(-0.0f);
    const __m256 a = _mm256_sqrt_ps(dot_x8(x21, y21, z21, x21, y21, z21));
    const __m256 b = _mm256_sqrt_ps(dot_x8(x31, y31, z31, x31, y31, z31));
    const __m256 c = _mm256_sqrt_ps(dot_x8(x23, y23, z23, x23, y23, z23));
    const __m256 cos1 = _mm256_div_ps(_mm256_andnot_ps(sign, dot_x8(x21, y21, z21, x31, y31, z31)),
                                      _mm256_mul_ps(a, b));
    const __m256 cos2 = _mm256_div_ps(_mm256_andnot_ps(sign, dot_x8(x23, y23, z23, x31, y31, z31)),
                                      _mm256_mul_ps(c, b));
    const __m256 cos3 = _mm256_div_ps(_mm256_andnot_ps(sign, dot_x8(x23, y23, z23, x21, y21, z21)),
                                      _mm256_mul_ps(c, a));
    const __m256 s = _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(a, b), c), _mm256_set1_ps(0.5f));
    const __m256 heron =
        _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(s, _mm256_sub_ps(s, a)), _mm256_sub_ps(s, b)),
                      _mm256_sub_ps(s, c));
    alignas(32) float lanes[7][8];
    _mm256_store_ps(lanes[0], a);
    _mm256_store_ps(lanes[1], b);
    _mm256_store_ps(lanes[2], c);
    _mm256_store_ps(lanes[3], cos1);
    _mm256_store_ps(lanes[4], cos2);
    _mm256_store_ps(lanes[5], cos3);
    _mm256_store_ps(lanes[6], heron);
    for (int k = 0; k < 8; ++k)
        out[k] = {lanes[0][k], lanes[1][k], lanes[2][k], lanes[3][k],
                  lanes[4][k], lanes[5][k], lanes[6][k]};
}

bool cpu_has_avx2() {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2");
}

/// Bins a triple of the fast sampler. False when it is rejected (degenerate, or an angle bin
/// outside [0, 63]).
inline bool triangle_fast(const TripleGeometry& g, const AngleBins& bins, Triangle& t) {
    if (!(g.heron > kMinHeronProduct)) return false;
    const int t1 = bins(g.cos1), t2 = bins(g.cos2), t3 = bins(g.cos3);
    if ((t1 | t2 | t3) >= kEsfBins) return false;
    t.angle_bin = {static_cast<std::uint8_t>(t1), static_cast<std::uint8_t>(t2),
                   static_cast<std::uint8_t>(t3)};
    t.d2 = {g.a, g.b, g.c};
    t.d3 = std::sqrt(std::sqrt(g.heron));
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
    // The fast sampler reads the points one axis at a time (for gathers): copied in this pass.
    ws.xs.resize(pcl ? 0 : n);
    ws.ys.resize(pcl ? 0 : n);
    ws.zs.resize(pcl ? 0 : n);
    for (std::size_t i = 0; i < n; ++i) {
        const auto& p = ws.scaled[i];
        ws.cells[i] = pack_cell(cell_of(p.x(), half), cell_of(p.y(), half), cell_of(p.z(), half));
        ws.grid.set(ws.cells[i]);
        if (!pcl) {
            ws.xs[i] = p.x();
            ws.ys[i] = p.y();
            ws.zs[i] = p.z();
        }
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
        static const bool avx2 = cpu_has_avx2();  // CPU features do not change while running
        // Attempts are drawn eight at a time and consumed in order; draws past the last accepted
        // triple are discarded, so the result is that of drawing one attempt at a time.
        constexpr int kBatch = 8;
        std::uint32_t i1[kBatch], i2[kBatch], i3[kBatch];
        TripleGeometry geometry[kBatch];
        while (accepted < samples) {
            for (int k = 0; k < kBatch; ++k) {
                const std::uint64_t r1 = random(), r2 = random();
                i1[k] = bounded(static_cast<std::uint32_t>(r1 >> 32), count);
                i2[k] = bounded(static_cast<std::uint32_t>(r1), count);
                i3[k] = bounded(static_cast<std::uint32_t>(r2 >> 32), count);
            }
            if (avx2) {
                triple_geometry_x8(ws.xs.data(), ws.ys.data(), ws.zs.data(), i1, i2, i3, geometry);
            } else {
                for (int k = 0; k < kBatch; ++k)
                    geometry[k] = triple_geometry(ws.xs.data(), ws.ys.data(), ws.zs.data(), i1[k],
                                                  i2[k], i3[k]);
            }
            for (int k = 0; k < kBatch && accepted < samples; ++k) {
                if (++attempts > max_attempts) throw_degenerate(n, accepted, max_attempts);
                if (i1[k] == i2[k] || i1[k] == i3[k] || i2[k] == i3[k]) continue;
                if (!triangle_fast(geometry[k], bins, ws.triangles[accepted])) continue;
                record(i1[k], i2[k], i3[k]);
            }
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
    // Four interleaved copies of the histograms (triangle t counts into copy t % 4), summed at
    // the end: consecutive increments of one bin then do not wait on each other's stores.
    constexpr std::size_t kCopies = 4;
    std::uint32_t copies[kCopies][kEsfBlocks][kEsfBins] = {};
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
        auto& h = copies[t % kCopies];
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
    std::uint32_t h[kEsfBlocks][kEsfBins];
    for (int b = 0; b < kEsfBlocks; ++b)
        for (int i = 0; i < kEsfBins; ++i) {
            std::uint32_t total = 0;
            for (const auto& copy : copies) total += copy[b][i];
            h[b][i] = total;
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
