#pragma once
// Internal to the descriptors module: the PCL baselines module behind make_descriptor() and the
// checks every descriptor shares. No PCL types here.

#include <memory>
#include <span>
#include <string>

#include "esf/core/point_cloud.hpp"
#include "esf/descriptors/descriptor.hpp"

#define ESF_BASELINES_EXPORT __attribute__((visibility("default")))

namespace esf::detail {

/// The finite points of `points`. Throws std::invalid_argument "<name>: ..." when fewer than 3
/// remain, when they are all identical or all on one line.
Points describable_points(std::span<const Eigen::Vector3f> points, const std::string& name);

/// Scales a signature to sum 1. Returns false when it cannot be: a value is not finite or
/// negative, or the sum is 0.
bool normalise_signature(Signature& signature);

/// The baselines module (libesf_baselines.so, PCL inside): what it exports under the C name
/// esf_baseline_module. Built from the same sources as the library that loads it; `abi` guards
/// against a module of another build.
inline constexpr int kBaselineModuleAbi = 1;
struct BaselineModule {
    int abi = 0;
    /// The baseline `info.name` (pcl-esf, vfh, cvfh, our-cvfh, gasd, shot) with `info` as its
    /// info, or nullptr for another name. Options are validated by the caller.
    std::unique_ptr<GlobalDescriptor> (*make)(const DescriptorInfo& info,
                                              const DescriptorOptions& options) = nullptr;
};

/// The loaded baselines module. Loaded once per process on first use (the dynamic loader's
/// state is process-wide anyway) from, in order: $ESF_BASELINES (a file), lib/esf/ beside the
/// binary's directory (an installed tree), the build tree's lib/ and the installed libdir.
/// Throws std::invalid_argument naming `name` and how to get the module when none loads.
const BaselineModule& baseline_module(const std::string& name);

/// Whether the baselines module can be loaded (false when this build has none).
bool baseline_module_available();
}  // namespace esf::detail
