#include "esf/descriptors/descriptor.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>

#include "descriptors/cell_features.hpp"
#include "descriptors/pcl/baseline_descriptors.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/descriptors/surface_angles.hpp"

namespace esf {

GlobalDescriptor::~GlobalDescriptor() = default;

namespace detail {

Points describable_points(std::span<const Eigen::Vector3f> points, const std::string& name) {
    FinitePoints finite = drop_non_finite(points);
    const std::size_t n = finite.points.size();
    if (n < 3) {
        std::string msg = name + ": needs at least 3 finite points, got " + std::to_string(n);
        if (finite.dropped) msg += " (" + std::to_string(finite.dropped) + " non-finite dropped)";
        throw std::invalid_argument(msg);
    }
    const Points& p = finite.points;
    if (std::all_of(p.begin(), p.end(), [&](const Eigen::Vector3f& q) { return q == p[0]; }))
        throw std::invalid_argument(name + ": degenerate cloud: all " + std::to_string(n) +
                                    " points are identical");
    // Collinear when the second principal variance vanishes next to the first (the test of
    // compute_esf), accumulated in double about the mean.
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& q : p) mean += q.cast<double>();
    mean /= static_cast<double>(n);
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const auto& q : p) {
        const Eigen::Vector3d d = q.cast<double>() - mean;
        covariance += d * d.transpose();
    }
    const Eigen::Vector3d eigenvalues =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly)
            .eigenvalues();  // ascending
    if (eigenvalues[1] <= 1e-10 * eigenvalues[2])
        throw std::invalid_argument(name + ": degenerate cloud: all " + std::to_string(n) +
                                    " points lie on one line");
    return std::move(finite.points);
}

bool normalise_signature(Signature& signature) {
    double sum = 0.0;
    for (const float v : signature) {
        if (!std::isfinite(v) || v < 0.0f) return false;
        sum += v;
    }
    if (!(sum > 0.0)) return false;
    for (float& v : signature) v = static_cast<float>(v / sum);
    return true;
}

}  // namespace detail

namespace {

/// `info` with ESF's ten blocks of kEsfBins bins (esf_block_names()), then the `extra` blocks.
DescriptorInfo with_esf_blocks(DescriptorInfo info, std::span<const int> extra_sizes = {},
                               std::span<const char* const> extra_names = {}) {
    for (const char* name : esf_block_names()) {
        info.blocks.push_back(kEsfBins);
        info.block_names.emplace_back(name);
    }
    info.blocks.insert(info.blocks.end(), extra_sizes.begin(), extra_sizes.end());
    info.block_names.insert(info.block_names.end(), extra_names.begin(), extra_names.end());
    return info;
}

/// A registry entry without blocks (with_esf_blocks() or the caller adds them).
DescriptorInfo make_info(std::string name, int dimension, bool multi_signature, bool deterministic,
                         std::string description, int version, int sketch_group = 0) {
    DescriptorInfo info;
    info.name = std::move(name);
    info.dimension = dimension;
    info.multi_signature = multi_signature;
    info.deterministic = deterministic;
    info.description = std::move(description);
    info.version = version;
    info.sketch_group = sketch_group;
    return info;
}

DescriptorInfo with_blocks(DescriptorInfo info, std::vector<int> sizes,
                           std::vector<std::string> names) {
    info.blocks = std::move(sizes);
    info.block_names = std::move(names);
    return info;
}

/// An EsfEstimatorPool whose errors name the descriptor ("<name>: " in front). The estimator
/// drops non-finite points itself and rejects what describable_points() rejects, in the same
/// words.
class EstimatorPool {
  public:
    explicit EstimatorPool(const EsfOptions& options) : pool_(options) {}

    EsfResult compute(std::span<const Eigen::Vector3f> points, const std::string& name) const {
        try {
            return pool_.compute(points);
        } catch (const std::invalid_argument& e) {
            // "ESF needs ..." -> "<name>: needs ...", the form of the other descriptors' errors.
            std::string what = e.what();
            if (what.rfind("ESF ", 0) == 0) what.erase(0, 4);
            throw std::invalid_argument(name + ": " + what);
        }
    }

  private:
    EsfEstimatorPool pool_;
};

EsfOptions fast_esf_options(const DescriptorOptions& options) {
    EsfOptions out;
    out.samples = options.samples;
    out.seed = options.seed;
    out.sampler = EsfSampler::kFast;
    out.kernels = options.kernels;
    return out;
}

/// The blocks esf-angles adds to ESF's: the six surface angle histograms, then the cylinder-box
/// contrast, all from the same surface cells.
constexpr std::array<int, kSurfaceAngleBlocks + 1> kSurfaceBlockSizes = {
    kSurfaceAngleBins,     kSurfaceAngleBins,     kSurfaceAngleBins, kSurfaceAngleBins,
    kSurfaceViewpointBins, kSurfaceVariationBins, kPrimitiveBins};
constexpr std::array<const char*, kSurfaceAngleBlocks + 1> kSurfaceBlockNames = {
    "alpha", "phi", "theta", "s", "beta", "sigma", kPrimitiveBlockName};

/// What each baseline computes: known without loading the module.
DescriptorInfo baseline_info(const std::string& name) {
    constexpr int v = kBaselineDescriptorVersion;
    if (name == "pcl-esf")
        return with_esf_blocks(
            make_info(name, kEsfSize, false, false,
                      "PCL 1.13 pcl::ESFEstimation (seeded from the clock: not reproducible)", v));
    if (name == "vfh") return make_info(name, 308, false, true, "PCL VFH (Rusu et al. 2010)", v);
    if (name == "cvfh")
        return make_info(name, 308, true, true,
                         "PCL CVFH, one signature per smooth region (Aldoma et al. 2011)", v);
    if (name == "our-cvfh")
        return make_info(name, 308, true, true,
                         "PCL OUR-CVFH, one signature per region and reference frame (Aldoma et "
                         "al. 2012)",
                         v);
    if (name == "gasd")
        return make_info(name, 512, false, true, "PCL GASD, shape only (Lima & Teichrieb 2016)", v);
    return make_info(name, 352, false, true,
                     "PCL SHOT at the centroid, radius covering the object (Tombari et al. 2010)",
                     v);
}

/// What each registered descriptor computes (the name is checked by the caller).
DescriptorInfo registered_info(const std::string& name) {
    if (name == "esf") {
        DescriptorInfo info = with_esf_blocks(make_info(
            "esf", kEsfSize, false, true,
            "Ensemble of Shape Functions (Wohlkinger & Vincze 2011), fast sampler, seeded",
            kEsfVersion));
        info.esf_options = true;
        return info;
    }
    if (name == "sdvs")
        return with_blocks(make_info("sdvs", 3 * kEsfBins, false, true,
                                     "SDVS: D2 split by voxel-line class IN, OUT, "
                                     "MIXED (Wohlkinger & Vincze 2011)",
                                     kEsfVersion),
                           {kEsfBins, kEsfBins, kEsfBins}, {"d2_in", "d2_out", "d2_mixed"});
    if (name == "d2")
        return make_info("d2", kEsfBins, false, true, "D2 shape distribution (Osada et al. 2002)",
                         kEsfVersion);
    if (name == "esf-angles") {
        DescriptorInfo info = with_esf_blocks(
            make_info("esf-angles", kEsfAnglesSize, false, true,
                      "ESF (Wohlkinger & Vincze 2011) + view-relative surface angle histograms "
                      "(VFH's angles, Rusu et al. 2010), seeded",
                      kEsfVersion * 100 + kSurfaceAnglesVersion, 1),
            kSurfaceBlockSizes, kSurfaceBlockNames);
        info.angles_weight = true;
        return info;
    }
    return baseline_info(name);
}

/// Our ESF (esf_descriptor.hpp), fast sampler.
class EsfGlobal final : public GlobalDescriptor {
  public:
    explicit EsfGlobal(const DescriptorOptions& options) : EsfGlobal(fast_esf_options(options)) {}
    explicit EsfGlobal(const EsfOptions& options) : info_(registered_info("esf")), pool_(options) {}
    const DescriptorInfo& info() const override { return info_; }

    std::vector<Signature> compute(std::span<const Eigen::Vector3f> points) const override {
        const EsfResult result = pool_.compute(points, info_.name);
        return {Signature(result.descriptor.begin(), result.descriptor.end())};
    }

  private:
    DescriptorInfo info_;
    EstimatorPool pool_;
};

/// SDVS (Wohlkinger & Vincze, "Shape distributions on voxel surfaces for 3D object
/// classification from depth images", ICSIPA 2011), the predecessor of ESF: the D2 shape
/// function with each distance classified by whether its line runs IN, OUT of or MIXED through
/// the occupied voxels. Here it is the D2-IN, D2-OUT and D2-MIXED blocks of one ESF run (same
/// sampler, seed and 64^3 grid, 3 x 20,000 distances), with ESF's block weights undone so that
/// the 192 bins are plain counts, then L1-normalised. `d2` sums the three blocks bin by bin:
/// Osada's D2 distance histogram (64 bins of distance / max distance) over the same pairs.
class D2Global final : public GlobalDescriptor {
  public:
    D2Global(const DescriptorOptions& options, bool split)
        : info_(registered_info(split ? "sdvs" : "d2")),
          pool_(fast_esf_options(options)),
          split_(split) {}
    const DescriptorInfo& info() const override { return info_; }

    std::vector<Signature> compute(std::span<const Eigen::Vector3f> points) const override {
        const EsfResult result = pool_.compute(points, info_.name);
        // Blocks 6, 7, 8 of ESF are D2-IN, D2-OUT, D2-MIXED, weighted 0.5, 2, 2 before ESF's
        // normalisation (docs/esf.md, "Histograms and output"); dividing by the weights gives
        // counts up to one common factor, which the normalisation below removes.
        constexpr int kFirstD2Block = 6;
        constexpr std::array<float, 3> kD2Weights = {0.5f, 2.0f, 2.0f};
        Signature signature(static_cast<std::size_t>(info_.dimension), 0.0f);
        for (int block = 0; block < 3; ++block) {
            for (int bin = 0; bin < kEsfBins; ++bin) {
                const float count = result.descriptor[static_cast<std::size_t>(
                                        (kFirstD2Block + block) * kEsfBins + bin)] /
                                    kD2Weights[static_cast<std::size_t>(block)];
                signature[static_cast<std::size_t>((split_ ? block * kEsfBins : 0) + bin)] += count;
            }
        }
        if (!detail::normalise_signature(signature))
            throw std::invalid_argument(info_.name + ": the distance histogram is empty");
        return {std::move(signature)};
    }

  private:
    DescriptorInfo info_;
    EstimatorPool pool_;
    bool split_;
};

/// ESF followed by the six surface angle histograms (surface_angles.hpp), every block with an
/// equal share: each of ESF's ten sub-histograms is scaled to sum 1 / (10 (1 + weight)) and each
/// angle histogram to weight / (6 (1 + weight)), so the signature sums to 1 and the L1 distance
/// of two signatures is a weighted mean of the blocks' own L1 distances. ESF's raw blocks carry
/// unequal mass (on the training views the three D2 blocks hold 0.14 to 0.23 each, the OUT
/// blocks of A3 and D3 under 0.02), so a few blocks decided the distance; with equal shares every
/// shape function counts the same (real views: +4 to +8 points of 1-NN, BENCHMARKS.md). The
/// weight sets how far the surface angles count next to ESF.
class EsfAnglesGlobal final : public GlobalDescriptor {
  public:
    explicit EsfAnglesGlobal(const DescriptorOptions& options)
        : info_(registered_info("esf-angles")),
          pool_(fast_esf_options(options)),
          weight_(options.angles_weight),
          primitive_weight_(options.primitive_weight),
          seed_(options.seed) {}
    const DescriptorInfo& info() const override { return info_; }

    std::vector<Signature> compute(std::span<const Eigen::Vector3f> points) const override {
        const EsfResult esf = pool_.compute(points, info_.name);
        const detail::SurfaceCells cells =
            detail::surface_cells(points, SurfaceAngleOptions{}.cell_size, info_.name);
        const SurfaceAngleHistograms angles = detail::surface_angles(cells);
        PrimitiveFitOptions fit_options;
        fit_options.seed = seed_;
        const PrimitiveHistogram primitive =
            primitive_histogram(detail::fit_primitives(cells.cells, cells.cell_size, fit_options));
        Signature signature(static_cast<std::size_t>(kEsfAnglesSize), 0.0f);
        const double total = 1.0 + weight_ + primitive_weight_;
        const double block_share = 1.0 / (kEsfBlocks * total);
        for (std::size_t begin = 0; begin < esf.descriptor.size(); begin += kEsfBins) {
            double mass = 0.0;
            for (std::size_t i = begin; i < begin + kEsfBins; ++i) mass += esf.descriptor[i];
            if (mass <= 0.0) continue;  // an empty block (no OFF-surface line, say) stays empty
            for (std::size_t i = begin; i < begin + kEsfBins; ++i)
                signature[i] = static_cast<float>(esf.descriptor[i] / mass * block_share);
        }
        const double angle_scale = weight_ / (kSurfaceAngleBlocks * total);
        for (std::size_t i = 0; i < angles.size(); ++i)
            signature[esf.descriptor.size() + i] = static_cast<float>(angles[i] * angle_scale);
        const double primitive_scale = primitive_weight_ / total;
        for (std::size_t i = 0; i < primitive.size(); ++i)
            signature[esf.descriptor.size() + angles.size() + i] =
                static_cast<float>(primitive[i] * primitive_scale);
        return {std::move(signature)};
    }

  private:
    DescriptorInfo info_;
    EstimatorPool pool_;
    double weight_;
    double primitive_weight_;
    std::uint64_t seed_;
};

constexpr std::array<const char*, 10> kNames = {"esf", "esf-angles", "pcl-esf",  "sdvs", "d2",
                                                "vfh", "cvfh",       "our-cvfh", "gasd", "shot"};

void validate(const DescriptorOptions& options) {
    if (!(std::isfinite(options.primitive_weight) && options.primitive_weight >= 0.0))
        throw std::invalid_argument(
            "descriptor options: primitive_weight must be finite and >= 0, got " +
            std::to_string(options.primitive_weight));
    if (!(std::isfinite(options.angles_weight) && options.angles_weight >= 0.0))
        throw std::invalid_argument(
            "descriptor options: angles_weight must be finite and >= 0, got " +
            std::to_string(options.angles_weight));
    if (options.samples < 1)
        throw std::invalid_argument("descriptor options: samples must be at least 1, got " +
                                    std::to_string(options.samples));
    if (!(std::isfinite(options.leaf_factor) && options.leaf_factor >= 0.0f))
        throw std::invalid_argument(
            "descriptor options: leaf_factor must be finite and >= 0, got " +
            std::to_string(options.leaf_factor));
    if (!(std::isfinite(options.normal_radius_factor) && options.normal_radius_factor > 0.0f))
        throw std::invalid_argument(
            "descriptor options: normal_radius_factor must be finite and > 0, got " +
            std::to_string(options.normal_radius_factor));
}

/// The PCL baselines, computed by the baselines module (baseline_descriptors.cpp).
bool is_baseline(const std::string& name) {
    return name == "pcl-esf" || name == "vfh" || name == "cvfh" || name == "our-cvfh" ||
           name == "gasd" || name == "shot";
}

}  // namespace

std::vector<std::string> descriptor_names() { return {kNames.begin(), kNames.end()}; }

void check_descriptor_name(const std::string& name) {
    if (std::find(kNames.begin(), kNames.end(), name) != kNames.end()) return;
    std::string valid;
    for (const char* n : kNames) valid += (valid.empty() ? "" : ", ") + std::string(n);
    throw std::invalid_argument("unknown descriptor '" + name + "' (valid: " + valid + ")");
}

std::unique_ptr<GlobalDescriptor> make_descriptor(const std::string& name,
                                                  const DescriptorOptions& options) {
    check_descriptor_name(name);
    validate(options);
    if (name == "esf") return std::make_unique<EsfGlobal>(options);
    if (name == "esf-angles") return std::make_unique<EsfAnglesGlobal>(options);
    if (name == "sdvs") return std::make_unique<D2Global>(options, true);
    if (name == "d2") return std::make_unique<D2Global>(options, false);
    std::unique_ptr<GlobalDescriptor> baseline =
        detail::baseline_module(name).make(baseline_info(name), options);
    if (!baseline) throw std::invalid_argument(name + ": the baselines module does not know it");
    return baseline;
}

std::unique_ptr<GlobalDescriptor> make_esf_descriptor(const EsfOptions& options) {
    return std::make_unique<EsfGlobal>(options);  // its pool checks the options
}

void check_descriptor_options(const std::string& name, const DescriptorOptions& options) {
    check_descriptor_name(name);
    validate(options);
}

void require_descriptor(const std::string& name) {
    check_descriptor_name(name);
    if (is_baseline(name)) detail::baseline_module(name);
}

bool descriptor_available(const std::string& name) {
    check_descriptor_name(name);
    return !is_baseline(name) || detail::baseline_module_available();
}

DescriptorInfo descriptor_info(const std::string& name) {
    check_descriptor_name(name);
    return registered_info(name);
}

int stored_descriptor_version(const std::string& name) { return descriptor_info(name).version; }

int descriptor_sketch_group(const std::string& name) {
    const bool known = std::find(kNames.begin(), kNames.end(), name) != kNames.end();
    return known ? descriptor_info(name).sketch_group : 0;  // another kind: the index's default
}

std::vector<std::size_t> descriptor_blocks(const DescriptorInfo& info) {
    if (info.blocks.empty()) return {static_cast<std::size_t>(info.dimension)};
    return {info.blocks.begin(), info.blocks.end()};
}

std::vector<float> descriptor_dimension_weights(const DescriptorInfo& info,
                                                std::span<const float> stored) {
    const std::vector<std::size_t> blocks = descriptor_blocks(info);
    const auto dimension = static_cast<std::size_t>(info.dimension);
    for (const float w : stored)
        if (!(w > 0.0f) || !std::isfinite(w))
            throw std::invalid_argument(info.name + " weights must be finite and > 0, got " +
                                        std::to_string(w));
    if (stored.size() == dimension) return {stored.begin(), stored.end()};
    if (stored.size() != blocks.size())
        throw std::invalid_argument(info.name + " weights hold " + std::to_string(stored.size()) +
                                    " values, expected " + std::to_string(blocks.size()) +
                                    " (one per block) or " + std::to_string(dimension));
    std::vector<float> out;
    out.reserve(dimension);
    for (std::size_t b = 0; b < blocks.size(); ++b) out.insert(out.end(), blocks[b], stored[b]);
    return out;
}

}  // namespace esf
