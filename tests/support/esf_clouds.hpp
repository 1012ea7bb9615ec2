#pragma once
// A cloud and an error check shared by the ESF descriptor tests.

#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>

#include "esf/core/point_cloud.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"

namespace esf::test {

/// Front half of a cylinder with a lid: a partial view with IN, OUT and MIXED lines.
inline Points partial_cylinder(std::size_t count, std::uint32_t seed = 3) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    Points points(count);
    for (auto& p : points) {
        const float a = 3.14159f * unit(rng);
        if (unit(rng) < 0.8f) {
            p = {0.04f * std::cos(a), 0.12f * unit(rng), 0.04f * std::sin(a)};
        } else {
            const float r = 0.04f * std::sqrt(unit(rng));
            p = {r * std::cos(2 * a), 0.12f, r * std::sin(2 * a)};
        }
    }
    return points;
}

/// The message of the std::invalid_argument that compute_esf() throws, or "no error".
inline std::string esf_error_of(const Points& points, const EsfOptions& options = {}) {
    try {
        compute_esf(points, options);
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "no error";
}

}  // namespace esf::test
