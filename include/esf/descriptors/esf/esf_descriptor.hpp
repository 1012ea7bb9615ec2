#pragma once
// The Ensemble of Shape Functions descriptor (Wohlkinger & Vincze, ROBIO 2011, Sec. III).
//
// Ten 64-bin histograms of shape functions over random point triples: A3 (angles), D3 (sqrt of
// triangle area) and D2 (distances), each split by whether the lines between the points run
// IN, OUT of or MIXED through the occupied cells of a 64^3 voxel grid, plus the ratio histogram
// of the MIXED D2 lines. Output order: A3-IN, A3-OUT, A3-MIXED, D3-IN, D3-OUT, D3-MIXED, D2-IN,
// D2-OUT, D2-MIXED, D2-RATIO; L1-normalised to sum 1.
//
// Thread safety: compute_esf() and compute_esf_batch() are re-entrant; an EsfEstimator keeps a
// reusable workspace and must not be shared between threads.

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "esf/core/enum_names.hpp"
#include "esf/core/kernels.hpp"
#include "esf/core/point_cloud.hpp"

namespace esf {

inline constexpr int kEsfBins = 64;
inline constexpr int kEsfBlocks = 10;
inline constexpr int kEsfSize = kEsfBins * kEsfBlocks;  // 640

/// Descriptor version stored with databases; bump when the output of the default options changes.
inline constexpr int kEsfVersion = 2;

using EsfDescriptor = std::array<float, kEsfSize>;

/// Names of the ten blocks, in output order ("a3_in", ..., "d2_ratio").
const std::array<const char*, kEsfBlocks>& esf_block_names();

enum class EsfSampler {
    /// 16 xoshiro128++ streams seeded by SplitMix64: reproducible for a seed on every machine
    /// and thread count; the fast path (bit-packed grid, SIMD sampling and line tracing).
    kFast,
    /// glibc rand() model: bit for bit what pcl::ESFEstimation (PCL 1.13) computes after
    /// srand(seed). Slower; for validation against the reference.
    kPcl,
};

/// "fast", "pcl" (to_string, parse_enum<EsfSampler>).
template <>
struct EnumNames<EsfSampler> {
    static constexpr const char* what = "ESF sampler";
    static constexpr std::array<EnumName<EsfSampler>, 2> table{
        {{EsfSampler::kFast, "fast"}, {EsfSampler::kPcl, "pcl"}}};
};

/// Accepted point triples per description: the paper's 20,000, the default of every command,
/// binding and training run that samples point triples.
inline constexpr int kEsfSamples = 20000;

struct EsfOptions {
    int samples = kEsfSamples;  ///< accepted point triples
    int grid_size = 64;         ///< voxel grid side, 8..64 (the `pcl` sampler needs 64)
    std::uint64_t seed = 0;
    EsfSampler sampler = EsfSampler::kFast;
    /// Attempts allowed per requested sample before the cloud is declared degenerate
    /// (PCL loops forever there). Rejections are rare on real clouds (< 1 %).
    int max_attempts_per_sample = 64;
    /// Which kernels the fast sampler runs; each gives the same output bit for bit (for
    /// testing, for measuring the path another CPU would take, or to rule the kernels out).
    /// kBest: AVX-512 (F, BW, VL, DQ) kernels for the per-point passes, sampling, tracing and
    /// histograms, the tracer counting cells with VPOPCNTDQ where present and timing its
    /// versions on the first calls to keep the fastest (docs/esf.md); AVX2 kernels without
    /// AVX-512; portable code otherwise. kAvx512, kAvx2: at most those (narrower where the CPU
    /// lacks them), the tracer without trials; kPortable: no SIMD kernels.
    Kernels kernels = Kernels::kBest;
};

struct EsfResult {
    EsfDescriptor descriptor{};
    std::size_t points = 0;          ///< finite points used
    std::size_t dropped_points = 0;  ///< non-finite points removed first
    std::size_t attempts = 0;        ///< triples drawn, accepted or not
};

/// Computes ESF descriptors with a reusable workspace (no allocation after the first call of a
/// given size). Throws std::invalid_argument for options out of range (in the constructor) and
/// for clouds that have no descriptor: fewer than 3 finite points, all points identical, all on
/// one line (no non-degenerate triangle within the attempt budget), coordinates too large.
/// Throws the std::invalid_argument that EsfEstimator::compute() throws for a cloud with fewer
/// than 3 finite points ("ESF needs at least 3 finite points, got 1 (2 non-finite dropped)");
/// does nothing for 3 or more. For callers that drop the non-finite points before computing
/// (read_finite_points()), so that the message still counts them.
void require_esf_points(std::size_t finite, std::size_t dropped);

class EsfEstimator {
  public:
    explicit EsfEstimator(const EsfOptions& options = {});
    ~EsfEstimator();
    EsfEstimator(EsfEstimator&&) noexcept;
    EsfEstimator& operator=(EsfEstimator&&) noexcept;

    EsfResult compute(std::span<const Eigen::Vector3f> points);
    const EsfOptions& options() const { return options_; }

  private:
    struct Workspace;
    EsfOptions options_;
    std::unique_ptr<Workspace> workspace_;
};

/// EsfEstimators for concurrent callers: compute() borrows a free estimator (or makes one) and
/// gives it back, so workspaces are reused (their set-up is about a quarter of the time on a
/// 15k-point cloud) but never shared. The output does not depend on which estimator computes it.
/// Thread safety: compute() may run concurrently from any number of threads.
class EsfEstimatorPool {
  public:
    /// Throws std::invalid_argument for options out of range.
    explicit EsfEstimatorPool(const EsfOptions& options = {});
    ~EsfEstimatorPool();

    /// As EsfEstimator::compute().
    EsfResult compute(std::span<const Eigen::Vector3f> points) const;
    const EsfOptions& options() const { return options_; }

  private:
    EsfOptions options_;
    mutable std::mutex mutex_;
    mutable std::vector<std::unique_ptr<EsfEstimator>> free_;
};

/// One-shot convenience: EsfEstimator(options).compute(points).
EsfResult compute_esf(std::span<const Eigen::Vector3f> points, const EsfOptions& options = {});

/// Outcome of one cloud of a batch: `error` is empty on success.
struct EsfBatchItem {
    EsfResult result;
    std::string error;
    bool ok() const { return error.empty(); }
};

/// Describes many clouds in parallel (threads = 0: all cores). Every cloud uses options.seed, so
/// the output does not depend on the thread count or on the other clouds. A cloud that cannot
/// be described gets its error message instead of throwing.
std::vector<EsfBatchItem> compute_esf_batch(std::span<const Points> clouds,
                                            const EsfOptions& options = {}, int threads = 0);

/// L1 distance between two descriptors (sum of absolute differences, accumulated in double).
double l1_distance(const EsfDescriptor& a, const EsfDescriptor& b);

}  // namespace esf
