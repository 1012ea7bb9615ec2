#pragma once
// A test cloud shared by the descriptor tests.

#include <cmath>

#include "esf/core/point_cloud.hpp"

namespace esf::test {

/// A square of side `side` on a regular 2 mm grid at depth `z`, centred on the optical axis,
/// facing the sensor.
inline Points facing_square(float side = 0.2f, float z = 1.0f) {
    Points points;
    const int steps = static_cast<int>(std::lround(side / 0.002f));
    for (int i = 0; i <= steps; ++i)
        for (int j = 0; j <= steps; ++j)
            points.emplace_back(-side / 2 + 0.002f * static_cast<float>(i),
                                -side / 2 + 0.002f * static_cast<float>(j), z);
    return points;
}

}  // namespace esf::test
