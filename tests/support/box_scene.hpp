#pragma once
// Organised test frames cast analytically: a pinhole camera (640 x 480 scaled by `scale`,
// Kinect v1 intrinsics) at the origin looking along +z, y down; a table plane y = table_y and
// axis-aligned boxes standing on it or on each other. Each pixel holds the nearest hit and its
// owner (0 = table, k + 1 = box k, -1 = nothing).

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "esf/core/point_cloud.hpp"

namespace esf::test {

struct Box {
    Eigen::Vector3f low, high;
};

struct CastScene {
    PointCloud cloud;
    std::vector<int> owner;
};

inline CastScene cast_boxes(const std::vector<Box>& boxes, float table_y, int scale = 1) {
    const std::uint32_t width = 640 / scale, height = 480 / scale;
    const float f = 525.0f / static_cast<float>(scale);
    const float cx = (static_cast<float>(width) - 1) / 2, cy = (static_cast<float>(height) - 1) / 2;
    CastScene scene;
    scene.cloud.width = width;
    scene.cloud.height = height;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (std::uint32_t v = 0; v < height; ++v)
        for (std::uint32_t u = 0; u < width; ++u) {
            const Eigen::Vector3f ray((static_cast<float>(u) - cx) / f,
                                      (static_cast<float>(v) - cy) / f, 1.0f);
            float best = std::numeric_limits<float>::infinity();
            int who = -1;
            if (ray.y() > 0) {
                const float t = table_y / ray.y();
                const Eigen::Vector3f p = t * ray;
                if (t < 3.0f && std::abs(p.x()) < 0.6f) {
                    best = t;
                    who = 0;
                }
            }
            for (std::size_t k = 0; k < boxes.size(); ++k) {
                float t0 = 0.0f, t1 = std::numeric_limits<float>::infinity();
                for (int a = 0; a < 3; ++a) {
                    const float lo = boxes[k].low[a] / ray[a], hi = boxes[k].high[a] / ray[a];
                    t0 = std::max(t0, std::min(lo, hi));
                    t1 = std::min(t1, std::max(lo, hi));
                }
                if (t0 <= t1 && t0 < best) {
                    best = t0;
                    who = static_cast<int>(k) + 1;
                }
            }
            scene.cloud.points.push_back(who < 0 ? Eigen::Vector3f(nan, nan, nan) : best * ray);
            scene.owner.push_back(who);
        }
    return scene;
}

}  // namespace esf::test
