#pragma once
// The project's one random mixer: SplitMix64 (Steele, Lea & Flood, "Fast splittable
// pseudorandom number generators", OOPSLA 2014). Every seed derivation and every small generator
// (RANSAC hypotheses, generated shapes, training views, ESF's sampler streams, query samplings)
// goes through these, so results depend only on the seeds, never on threads or platforms.

#include <cstddef>
#include <cstdint>

namespace esf::detail {

/// SplitMix64's increment (the golden ratio in 64-bit fixed point).
inline constexpr std::uint64_t kGoldenGamma = 0x9E3779B97F4A7C15ull;

/// SplitMix64's output function: a bijective 64-bit mixer.
constexpr std::uint64_t mix64(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/// One step of the generator: advances `state` by the increment and mixes it.
constexpr std::uint64_t splitmix64(std::uint64_t& state) { return mix64(state += kGoldenGamma); }

/// Uniform in [0, 1): the top 53 bits of the generator's next output.
constexpr double splitmix64_uniform(std::uint64_t& state) {
    return static_cast<double>(splitmix64(state) >> 11) * 0x1.0p-53;
}

/// The generator as an object.
class SplitMix64 {
  public:
    explicit constexpr SplitMix64(std::uint64_t state) : state_(state) {}

    constexpr std::uint64_t next() { return splitmix64(state_); }

    /// Uniform in [0, n) up to a bias below 2^-32 (n < 2^32).
    constexpr std::size_t below(std::size_t n) { return static_cast<std::size_t>(next() % n); }
    /// Uniform in [0, 1): the top 53 bits of the next output.
    constexpr double uniform() { return splitmix64_uniform(state_); }

  private:
    std::uint64_t state_;
};

}  // namespace esf::detail
