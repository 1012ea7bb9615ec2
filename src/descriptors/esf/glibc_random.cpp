#include "esf/descriptors/esf/glibc_random.hpp"

#include <array>

namespace esf {

// glibc's srandom_r for TYPE_3: r[0] = seed, r[i] = 16807 r[i-1] mod (2^31 - 1) by Schrage's
// method (signed), r[31..33] = r[0..2], then 310 outputs are discarded.
GlibcRandom::GlibcRandom(std::uint32_t seed) {
    std::array<std::int32_t, 34> r{};
    r[0] = static_cast<std::int32_t>(seed == 0 ? 1 : seed);
    for (int i = 1; i < 31; ++i) {
        const std::int32_t hi = r[i - 1] / 127773;
        const std::int32_t lo = r[i - 1] % 127773;
        std::int32_t word = 16807 * lo - 2836 * hi;
        if (word < 0) word += 2147483647;
        r[i] = word;
    }
    for (int i = 31; i < 34; ++i) r[i] = r[i - 31];
    for (int i = 0; i < kDegree; ++i) ring_[i] = static_cast<std::uint32_t>(r[i + 3]);
    pos_ = 0;
    for (int i = 34; i < 344; ++i) (*this)();
}

}  // namespace esf
