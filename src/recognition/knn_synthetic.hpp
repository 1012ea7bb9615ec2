#pragma once
// Synthetic descriptors for the tests and benchmarks of the k-NN index (internal, header only).
//
// esf_like_rows() draws random histograms that look like ESF descriptors: blocks of 64 bins,
// each a sum of one to three broad bumps sampled with counting noise (so the tails hold exact
// zeros), the counts split between IN / OUT / MIXED as ESF splits its samples, ESF's block
// weights, L1-normalised to sum 1. On 640 bins they match real ESF clouds in their statistics
// (largest bin about 0.05, about 560 non-zero bins). Row i depends only on (seed, i), so the
// data do not depend on the thread count.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/splitmix64.hpp"
#include "esf/core/parallel.hpp"

namespace esf::detail {

/// SplitMix64 as a counter-based generator: stream `stream` of `seed`.
class SplitMix {
  public:
    SplitMix(std::uint64_t seed, std::uint64_t stream)
        : state_(seed * kGoldenGamma ^ (stream + 1) * 0xD1B54A32D192ED03ull) {}
    std::uint64_t next() { return splitmix64(state_); }
    /// Uniform in [0, 1).
    double uniform() { return splitmix64_uniform(state_); }

  private:
    std::uint64_t state_;
};

/// One ESF-like histogram of out.size() bins (blocks of 64; the last one may be shorter).
inline void esf_like_row(std::uint64_t seed, std::uint64_t index, std::span<float> out) {
    constexpr std::array<double, 10> kBlockWeight = {0.5, 0.5, 0.5, 0.5, 0.5,
                                                     1.0, 0.5, 2.0, 2.0, 1.0};
    constexpr std::size_t kBins = 64;
    SplitMix rng(seed, index);
    std::array<double, 3> share{};
    for (double& s : share) s = 0.4 + rng.uniform();
    const double share_sum = share[0] + share[1] + share[2];
    const std::size_t blocks = (out.size() + kBins - 1) / kBins;
    double total = 0.0;
    for (std::size_t b = 0; b < blocks; ++b) {
        const std::size_t block = b % 10;
        const std::size_t cls = block < 9 ? block % 3 : 2;
        const double samples = (block < 3   ? 60000.0
                                : block < 9 ? 20000.0
                                            : 6000.0) *
                               share[cls] / share_sum;
        const int bumps = 1 + static_cast<int>(rng.uniform() * 3.0);
        std::array<double, 3> centre{}, width{}, height{};
        for (int j = 0; j < bumps; ++j) {
            centre[j] = -4.0 + 72.0 * rng.uniform();
            width[j] = 14.0 + 46.0 * rng.uniform();
            height[j] = 0.2 + rng.uniform();
        }
        const std::size_t begin = b * kBins;
        const std::size_t end = std::min(out.size(), begin + kBins);
        std::array<double, kBins> density{};
        double density_sum = 0.0;
        for (std::size_t i = begin; i < end; ++i) {
            double v = 0.0;
            for (int j = 0; j < bumps; ++j) {
                const double t = (static_cast<double>(i - begin) - centre[j]) / width[j];
                if (t * t < 1.0) v += height[j] * (1.0 - t * t) * (1.0 - t * t);
            }
            density[i - begin] = v;
            density_sum += v;
        }
        if (density_sum <= 0.0) {
            density[0] = 1.0;
            density_sum = 1.0;
        }
        for (std::size_t i = begin; i < end; ++i) {
            const double mean = density[i - begin] / density_sum * samples;
            // Counting noise with the Poisson standard deviation (a triangular variate).
            const double noise = (rng.uniform() + rng.uniform() - 1.0) * 2.449489742783178;
            const double x = mean + std::sqrt(mean) * noise;  // rounded half up, >= 0
            const double count =
                x > 0.0 ? static_cast<double>(static_cast<long long>(x + 0.5)) : 0.0;
            out[i] = static_cast<float>(count * kBlockWeight[block]);
            total += count * kBlockWeight[block];
        }
    }
    for (float& v : out) v = total > 0.0 ? static_cast<float>(v / total) : 0.0f;
}

/// `count` ESF-like rows of `dimension` bins, row-major.
inline std::vector<float> esf_like_rows(std::size_t count, std::size_t dimension,
                                        std::uint64_t seed, int threads = 0) {
    std::vector<float> rows(count * dimension);
    parallel_for(count, threads, [&](std::size_t i) {
        esf_like_row(seed, i, std::span<float>(rows.data() + i * dimension, dimension));
    });
    return rows;
}

}  // namespace esf::detail
