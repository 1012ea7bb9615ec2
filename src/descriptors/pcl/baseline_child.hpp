#pragma once
// Internal: our-cvfh in a helper process. PCL 1.13's OURCVFHEstimation aborts (an Eigen
// assertion) or writes out of bounds when a smooth region keeps a single point after its
// refinement: the region's reference frame divides by a zero weight sum. Real views of round
// objects do this. The baselines module therefore runs it in `esf_baseline_child`, a small
// executable started with posix_spawn (never fork() of a process with worker threads), so that
// such a cloud fails alone.
//
// Protocol, native byte order. Request on the child's stdin:
//   "ESFC" | u64 points | points x (f32 x, f32 y, f32 z) | f32 leaf_factor |
//   f32 normal_radius_factor | u8 remove_outliers
// Reply on its stdout, then exit status 0:
//   u64 status (0 ok, 1 error) | u64 a | u64 b | payload
//   ok:    a signatures of b floats, a x b f32
//   error: a bytes of message (std::invalid_argument's text)

#include <cstdint>
#include <string>
#include <vector>

#include "esf/core/point_cloud.hpp"
#include "esf/descriptors/descriptor.hpp"

namespace esf::detail {

/// our-cvfh computed in this process (the child's work; may abort on PCL's defect).
std::vector<Signature> our_cvfh_signatures(const Points& points, const DescriptorOptions& options,
                                           const std::string& name);

/// The request for `points` and `options`.
std::string encode_child_request(const Points& points, const DescriptorOptions& options);
/// Decodes a request; throws std::invalid_argument for a malformed one.
void decode_child_request(const std::string& bytes, Points& points, DescriptorOptions& options);

/// The reply for signatures, or for an error message.
std::string encode_child_reply(const std::vector<Signature>& signatures);
std::string encode_child_error(const std::string& message);

}  // namespace esf::detail
