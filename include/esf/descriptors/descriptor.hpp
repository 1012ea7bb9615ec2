#pragma once
// One interface through which every global descriptor is computed: ESF and the baselines the
// evaluation compares it with (Wohlkinger & Vincze, ROBIO 2011, Sec. IV).
//
//   name       dim  signatures  what
//   esf        640  1           our ESF (fast sampler, seeded)
//   esf-angles 732  1           ESF + view-relative surface angle histograms (surface_angles.hpp)
//                               + the cylinder-box contrast (primitive_fit.hpp)
//   pcl-esf    640  1           pcl::ESFEstimation of PCL 1.13 (time-seeded: not reproducible)
//   sdvs       192  1           D2 split by voxel-line class IN, OUT, MIXED (SDVS)
//   d2          64  1           the plain D2 shape distribution (Osada et al. 2002)
//   vfh        308  1           pcl::VFHEstimation (Rusu et al. 2010)
//   cvfh       308  1 or more   pcl::CVFHEstimation, one per smooth region (Aldoma et al. 2011)
//   our-cvfh   308  1 or more   pcl::OURCVFHEstimation, one per region and reference frame
//                               (Aldoma et al. 2012)
//   gasd       512  1           pcl::GASDEstimation, shape only (Lima & Teichrieb 2016)
//   shot       352  1           pcl::SHOTEstimation at the centroid with a radius covering the
//                               whole object (Tombari et al. 2010, used as a global descriptor)
//
// Every signature is finite, non-negative and L1-normalised to sum 1, so that L1 distances are
// comparable across descriptors. Input points are in the sensor frame (the camera at the origin
// looking along +z); non-finite points are dropped first.
//
// The PCL baselines (vfh, cvfh, our-cvfh, gasd, shot) share the preprocessing of PCL's global
// recognition pipeline (pcl::rec_3d_framework): r = median over the points of (sum of the
// distances to the 8 nearest neighbours) / 9, the framework's "mesh resolution"; voxel grid with
// leaf = 3 r; points with fewer than 5 neighbours within the normal radius removed; normals by
// pcl::NormalEstimation with radius = 3 leaves (the ratio of PCL's CVFH defaults, 5 mm leaf,
// 15 mm radius), oriented towards the sensor; points without a normal dropped. DescriptorOptions
// holds the factors; src/descriptors/pcl/baseline_descriptors.cpp lists each baseline's parameters.
//
// Errors: every failure is a std::invalid_argument whose message starts with the descriptor
// name ("vfh: ..."): fewer than 3 finite points, all points identical, all on one line, too few
// points left after the preprocessing, or a signature that comes out non-finite.
//
// Thread safety: compute() is const and may run concurrently on one object from any number of
// threads; each call builds its own PCL objects. pcl-esf serialises its calls (PCL draws from
// the process-global rand(), reseeded from time() on every call), so it is thread-safe but
// neither reproducible nor parallel. our-cvfh runs PCL in a helper process per call
// (esf_baseline_child beside the module, started with posix_spawn, never fork()): PCL 1.13's
// OURCVFHEstimation aborts (or writes out of bounds) when a refined smooth region keeps a single
// point, which real views of round objects do; such a cloud then fails alone with a
// std::invalid_argument. PCL prints its own warnings (e.g. OUR-CVFH's "Both axes
// are equally easy/difficult to disambiguate") through pcl::console; an application silences
// them with pcl::console::setVerbosityLevel(pcl::console::L_ERROR).

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "esf/core/kernels.hpp"
#include "esf/core/point_cloud.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/descriptors/primitive_fit.hpp"
#include "esf/descriptors/surface_angles.hpp"

namespace esf {

/// The version train() stores for the baselines (DescriptorInfo::version).
inline constexpr int kBaselineDescriptorVersion = 1;
/// Version of what "esf-angles" adds to ESF (the surface angle histograms and how the blocks are
/// scaled); that descriptor's stored version is kEsfVersion * 100 + this, so that a change of
/// either part is refused. 1: ESF's blocks as ESF scales them; 2: every ESF block an equal share;
/// 3: surface angle cells of 7 mm instead of 1 cm; 4: the primitive fit block
/// (primitive_fit.hpp).
inline constexpr int kSurfaceAnglesVersion = 4;

/// "esf-angles": ESF's ten 64-bin blocks, each scaled to an equal share, then the six surface
/// angle histograms, weighted kEsfAnglesWeight in all against ESF's 1, then the primitive fit's
/// cylinder-box contrast (primitive_fit.hpp), weighted kEsfPrimitiveWeight against ESF's 1; the
/// signature sums to 1.
inline constexpr int kEsfAnglesSize = kEsfSize + kSurfaceAngleSize + kPrimitiveBins;
inline constexpr double kEsfAnglesWeight = 1.0;
inline constexpr double kEsfPrimitiveWeight = 0.1;

/// What a descriptor computes.
struct DescriptorInfo {
    std::string name;              ///< registry name: "esf", "vfh", ...
    int dimension = 0;             ///< floats per signature
    bool multi_signature = false;  ///< may return several signatures per cloud (CVFH, OUR-CVFH)
    bool deterministic = true;     ///< the same input and options give the same output
    std::string description;       ///< one line: method and reference
    /// Sub-histograms whose L1 distances may be weighted apart (weight learning, block
    /// weights): their sizes in order, summing to `dimension`; empty means one block.
    std::vector<int> blocks;
    std::vector<std::string> block_names;  ///< one per block ("D2-IN", "alpha", ...)
    /// The version train() stores and Recognizer requires: kEsfVersion for esf, sdvs and d2
    /// (blocks of ESF's sampler), kEsfVersion * 100 + kSurfaceAnglesVersion for esf-angles,
    /// kBaselineDescriptorVersion for the PCL baselines.
    int version = 0;
    /// The sketch group (KnnIndexOptions::sketch_group) that searches its signatures fastest:
    /// 1 for esf-angles, whose distances lie closer together than ESF's (with the default, sums
    /// of 12 bins, a search computes exact distances for about a fifth of the views; with 1, an
    /// 8-bit copy of every bin, 768 bytes a view, for few: the real objects of a six-object scene
    /// match in 2.0 ms against 2.8 ms with sums of 2 bins, BENCHMARKS.md), 0 (the default) for
    /// the others.
    int sketch_group = 0;
    /// Configured by ESF's own options (EsfOptions: sampler, grid, attempt budget) rather than
    /// by DescriptorOptions: "esf" (make_esf_descriptor()).
    bool esf_options = false;
    /// Uses DescriptorOptions::angles_weight and primitive_weight: "esf-angles".
    bool angles_weight = false;
};

/// descriptor_info(name).version (throws for an unknown name).
int stored_descriptor_version(const std::string& name);
/// descriptor_info(name).sketch_group; 0 for a name the registry does not know.
int descriptor_sketch_group(const std::string& name);

/// What make_descriptor(name) computes, without computing anything. Throws like make_descriptor.
DescriptorInfo descriptor_info(const std::string& name);

/// The block sizes of `info` (one block of `dimension` when it lists none).
std::vector<std::size_t> descriptor_blocks(const DescriptorInfo& info);

/// Per-dimension weights from stored weights of `info`'s descriptor: one per block (expanded
/// over the block's bins) or one per dimension (as they are). Throws std::invalid_argument for
/// another count or a weight that is not finite and > 0.
std::vector<float> descriptor_dimension_weights(const DescriptorInfo& info,
                                                std::span<const float> stored);

struct DescriptorOptions {
    /// esf, sdvs, d2: seed of the triple sampler (pcl-esf is seeded from the clock by PCL).
    std::uint64_t seed = 0;
    /// esf, sdvs, d2: accepted point triples (pcl-esf always uses 20,000).
    int samples = kEsfSamples;
    /// PCL baselines: voxel-grid leaf in units of the mesh resolution r (0: no downsampling).
    float leaf_factor = 3.0f;
    /// PCL baselines: normal radius (also CVFH's cluster tolerance) in units of the leaf
    /// (in units of r when leaf_factor is 0).
    float normal_radius_factor = 3.0f;
    /// PCL baselines: drop points with fewer than 5 neighbours within the normal radius.
    bool remove_outliers = true;
    /// esf-angles: weight of the surface angle histograms against ESF's 1 (finite, >= 0).
    double angles_weight = kEsfAnglesWeight;
    /// esf-angles: weight of the primitive fit block against ESF's 1 (finite, >= 0).
    double primitive_weight = kEsfPrimitiveWeight;
    /// esf, esf-angles, sdvs, d2: the kernels of the triple sampler (EsfOptions::kernels; every
    /// set gives the same signatures).
    Kernels kernels = Kernels::kBest;
};

/// One descriptor vector (its length is info().dimension).
using Signature = std::vector<float>;

/// A global descriptor: a cloud in, one or more signatures out.
class GlobalDescriptor {
  public:
    virtual ~GlobalDescriptor();
    virtual const DescriptorInfo& info() const = 0;
    /// One signature per cloud, or (CVFH, OUR-CVFH) one per smooth region / reference frame,
    /// each finite, non-negative, of info().dimension floats summing to 1. Throws
    /// std::invalid_argument naming the descriptor for input it cannot describe.
    virtual std::vector<Signature> compute(std::span<const Eigen::Vector3f> points) const = 0;
};

/// Creates the descriptor `name` (one of descriptor_names()). Throws std::invalid_argument for
/// an unknown name (the message lists the valid ones), options out of range, or a PCL baseline
/// when the baselines module cannot be loaded (the message says how to get it).
std::unique_ptr<GlobalDescriptor> make_descriptor(const std::string& name,
                                                  const DescriptorOptions& options = {});

/// Descriptor "esf" with every one of ESF's options (sampler, grid, attempt budget, samples,
/// seed), as training stores it; make_descriptor("esf", options) is the same with the fast
/// sampler and a 64^3 grid. Throws std::invalid_argument for options out of range.
std::unique_ptr<GlobalDescriptor> make_esf_descriptor(const EsfOptions& options);

/// The registered names, in the order of the table above.
std::vector<std::string> descriptor_names();

/// Throws std::invalid_argument "unknown descriptor 'NAME' (valid: ...)" unless `name` is one of
/// descriptor_names(): the one check of a name, wherever it comes from (an option, a database).
void check_descriptor_name(const std::string& name);

/// Checks what make_descriptor(name, options) checks before computing anything: the name and
/// the options' ranges. Throws std::invalid_argument like make_descriptor. Needs no module.
void check_descriptor_options(const std::string& name, const DescriptorOptions& options);

/// Whether make_descriptor(name) can work in this build: always for esf, esf-angles, sdvs and
/// d2; for the PCL baselines only when the baselines module (libesf_baselines.so, built with
/// -DESF_WITH_PCL=ON) can be loaded. Throws std::invalid_argument for an unknown name.
bool descriptor_available(const std::string& name);

/// Throws what make_descriptor(name) would when the descriptor cannot be made in this build (an
/// unknown name, or a PCL baseline without its module; the message says how to get it).
void require_descriptor(const std::string& name);

}  // namespace esf
