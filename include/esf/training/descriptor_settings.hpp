#pragma once
// The registry's half that concerns databases: how a descriptor is configured, which settings a
// training run stores for it, how a recogniser reads them back, and the descriptor such a
// configuration makes. Every descriptor goes through these functions, ESF included, so that
// its settings are written and read in one place (the keys below).
//
//   every descriptor   descriptor, descriptor_version, descriptor_dimension, seed (the run's)
//   esf                esf_samples, esf_grid_size, esf_sampler, esf_max_attempts_per_sample
//                      (DescriptorInfo::esf_options: ESF's own options)
//   the others         descriptor_samples, descriptor_leaf_factor,
//                      descriptor_normal_radius_factor, descriptor_remove_outliers (0/1)
//   esf-angles         descriptor_angles_weight (DescriptorInfo::angles_weight)

#include <cstdint>
#include <memory>
#include <string>

#include "esf/descriptors/descriptor.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/training/database.hpp"

namespace esf {

/// A descriptor and its options: ESF's own (`esf`, for a descriptor with
/// DescriptorInfo::esf_options) or the registry's (`options`, for the others). The seeds inside
/// are ignored: make_descriptor() takes the seed to use.
struct DescriptorSetup {
    std::string name;
    EsfOptions esf;
    DescriptorOptions options;
};

/// The settings a training run stores for `setup` (without the run's seed). Throws
/// std::invalid_argument for an unknown descriptor.
Settings descriptor_settings(const DescriptorSetup& setup);

/// Reads the setup of descriptor `kind` from a database's settings; a missing key takes the
/// default of EsfOptions / DescriptorOptions, and the seeds become the stored `seed`. Throws
/// std::invalid_argument, naming the setting or the difference, for an unknown descriptor, a
/// version or dimension other than this build's ("retrain the database"), settings of the wrong
/// type or out of range.
DescriptorSetup read_descriptor_setup(const Settings& settings, const DescriptorKind& kind);

/// The seed a database's settings hold (`seed`: an integer, or decimal text above 2^63 - 1;
/// 0 when absent). Throws std::invalid_argument for anything else.
std::uint64_t stored_seed(const Settings& settings);

/// Checks `setup` before anything is computed (the name, the options' ranges). Throws
/// std::invalid_argument naming what is wrong. Needs no module.
void check_descriptor_setup(const DescriptorSetup& setup);

/// Name, version and dimension of what `setup` stores.
DescriptorKind descriptor_kind(const DescriptorSetup& setup);

/// The descriptor of `setup`, sampling with `seed`. Throws like make_descriptor().
std::unique_ptr<GlobalDescriptor> make_descriptor(const DescriptorSetup& setup, std::uint64_t seed);

}  // namespace esf
