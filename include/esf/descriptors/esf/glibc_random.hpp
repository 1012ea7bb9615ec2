#pragma once
// A model of glibc's rand() (TYPE_3 additive feedback generator, the default state size), so
// that the `pcl` ESF sampler can draw exactly the indices pcl::ESFEstimation draws after
// srand(seed). Each object has its own state: no global state, no interference with rand().

#include <array>
#include <cstdint>

namespace esf {

class GlibcRandom {
  public:
    /// Same sequence as glibc after srand(seed) (seed 0 behaves as seed 1).
    explicit GlibcRandom(std::uint32_t seed);

    /// The next value of rand(), in [0, 2^31 - 1].
    std::int32_t operator()() {
        const std::uint32_t value = ring_[pos_] + ring_[(pos_ + 28) % kDegree];  // r[i-31] + r[i-3]
        ring_[pos_] = value;
        pos_ = (pos_ + 1) % kDegree;
        return static_cast<std::int32_t>(value >> 1);
    }

  private:
    static constexpr int kDegree = 31;
    std::array<std::uint32_t, kDegree> ring_{};  // r[i-31] .. r[i-1], oldest at pos_
    int pos_ = 0;
};

}  // namespace esf
