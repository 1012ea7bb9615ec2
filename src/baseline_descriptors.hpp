#pragma once
// Internal to the descriptors module: the PCL baselines behind make_descriptor() and the checks
// every descriptor shares. No PCL types here.

#include <memory>
#include <span>
#include <string>

#include "esf/descriptor.hpp"
#include "esf/point_cloud.hpp"

namespace esf::detail {

/// The finite points of `points`. Throws std::invalid_argument "<name>: ..." when fewer than 3
/// remain, when they are all identical or all on one line.
Points describable_points(std::span<const Eigen::Vector3f> points, const std::string& name);

/// Scales a signature to sum 1. Returns false when it cannot be: a value is not finite or
/// negative, or the sum is 0.
bool normalise_signature(Signature& signature);

/// `info` with ESF's ten blocks of kEsfBins bins (esf_block_names()), then the `extra` blocks.
DescriptorInfo with_esf_blocks(DescriptorInfo info, std::span<const int> extra_sizes = {},
                               std::span<const char* const> extra_names = {});

/// The PCL baseline `name` (pcl-esf, vfh, cvfh, our-cvfh, gasd, shot), or nullptr when `name`
/// is not one of them. Options are validated by the caller.
std::unique_ptr<GlobalDescriptor> make_pcl_descriptor(const std::string& name,
                                                      const DescriptorOptions& options);

}  // namespace esf::detail
