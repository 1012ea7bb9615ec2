#pragma once
// The ESF reference algorithm written out plainly, step by step as docs/esf-spec.md (the
// shared ESF spec) states it: one loop, one 64^3 array of cells, glibc's own rand(). Slow and
// meant for small clouds; the oracle that the estimator's `pcl` sampler must match bin for bin.
//
// The float arithmetic is the reference's: Eigen 4-vectors (w = 0 for differences) for the edge
// lengths and directions, plain float sums for the centroid and the D2 distances.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "esf/core/point_cloud.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"

namespace esf::test {

namespace esf_reference_detail {

/// Half away from zero, in float.
inline float round_half_away(float x) {
    return x < 0.0f ? std::ceil(x - 0.5f) : std::floor(x + 0.5f);
}

/// The cell of a scaled coordinate: floor(v) + 32 below zero, ceil(v) + 31 from zero on.
inline int cell(float v) {
    return v < 0.0f ? static_cast<int>(std::floor(v) + 32.0f)
                    : static_cast<int>(std::ceil(v) + 31.0f);
}

struct Grid {
    std::vector<char> occupied = std::vector<char>(64 * 64 * 64, 0);
    char& at(int x, int y, int z) {
        return occupied[static_cast<std::size_t>((x * 64 + y) * 64 + z)];
    }
};

struct Line {
    int kind = 0;  ///< 0 IN, 1 OUT, 2 MIXED
    int occupied = 0, visited = 0;
    float ratio = 0.0f;
};

/// 3-D Bresenham from cell `from` to cell `to`, counting the visited and the occupied cells
/// (the start cell counted, the end cell not, at least one cell).
inline Line trace(Grid& grid, const std::array<int, 3>& from, const std::array<int, 3>& to) {
    std::array<int, 3> at = from, step{}, length{};
    for (int k = 0; k < 3; ++k) {
        step[k] = to[k] - from[k] < 0 ? -1 : 1;
        length[k] = std::abs(to[k] - from[k]);
    }
    int major = 2;
    if (length[0] >= length[1] && length[0] >= length[2])
        major = 0;
    else if (length[1] >= length[2])
        major = 1;
    // The minor axes in the order the reference steps them.
    const std::array<int, 2> minor = major == 0   ? std::array<int, 2>{1, 2}
                                     : major == 1 ? std::array<int, 2>{0, 2}
                                                  : std::array<int, 2>{1, 0};
    const int l = length[major];
    std::array<int, 2> error = {2 * length[minor[0]] - l, 2 * length[minor[1]] - l};
    Line line;
    for (int i = 1; i < l; ++i) {
        ++line.visited;
        line.occupied += grid.at(at[0], at[1], at[2]);
        for (int m = 0; m < 2; ++m) {
            if (error[m] > 0) {
                at[minor[m]] += step[minor[m]];
                error[m] -= 2 * l;
            }
        }
        for (int m = 0; m < 2; ++m) error[m] += 2 * length[minor[m]];
        at[major] += step[major];
    }
    ++line.visited;
    line.occupied += grid.at(at[0], at[1], at[2]);
    if (line.occupied >= line.visited - 1) {
        line.kind = 0;
    } else if (line.occupied <= 7) {
        line.kind = 1;
    } else {
        line.kind = 2;
        line.ratio = static_cast<float>(line.occupied) / static_cast<float>(line.visited);
    }
    return line;
}

}  // namespace esf_reference_detail

/// ESF of `input` (finite points, at least three, not all on one line) after srand(seed), with
/// `samples` accepted triangles: the ten blocks in output order, L1-normalised.
inline EsfDescriptor reference_esf(const Points& input, unsigned seed, int samples = 20000) {
    namespace d = esf_reference_detail;
    const std::size_t n = input.size();
    // Centre on the mean (float sums), scale the farthest point to 32 grid units.
    Eigen::Vector4f mean = Eigen::Vector4f::Zero();
    for (const auto& p : input) {
        mean[0] += p.x();
        mean[1] += p.y();
        mean[2] += p.z();
    }
    mean /= static_cast<float>(n);
    std::vector<Eigen::Vector4f> q(n);
    float farthest = 0.0f;
    for (std::size_t i = 0; i < n; ++i) {
        q[i] = {input[i].x() - mean[0], input[i].y() - mean[1], input[i].z() - mean[2], 1.0f};
        farthest = std::max(farthest,
                            std::sqrt(q[i][0] * q[i][0] + q[i][1] * q[i][1] + q[i][2] * q[i][2]));
    }
    const float scale = 1.0f / farthest * 32.0f;
    for (auto& p : q) p.head<3>() *= scale;

    // Every point's cell and its 26 neighbours are occupied.
    d::Grid grid;
    std::vector<std::array<int, 3>> cells(n);
    for (std::size_t i = 0; i < n; ++i) {
        cells[i] = {d::cell(q[i][0]), d::cell(q[i][1]), d::cell(q[i][2])};
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const int x = cells[i][0] + dx, y = cells[i][1] + dy, z = cells[i][2] + dz;
                    if (x >= 0 && y >= 0 && z >= 0 && x < 64 && y < 64 && z < 64)
                        grid.at(x, y, z) = 1;
                }
    }

    std::array<std::array<float, 64>, 10> h{};  // output order
    enum { kA3In, kA3Out, kA3Mixed, kD3In, kD3Out, kD3Mixed, kD2In, kD2Out, kD2Mixed, kRatio };
    std::vector<float> d2, d3, d3_weight;
    std::vector<int> d2_kind;
    const float half_pi = static_cast<float>(std::numbers::pi) / 2.0f;
    std::srand(seed);
    for (int accepted = 0, attempts = 0; accepted < samples; ++attempts) {
        if (attempts > 1000 * samples) throw std::invalid_argument("reference_esf: degenerate");
        const std::size_t i1 = static_cast<std::size_t>(std::rand()) % n;
        const std::size_t i2 = static_cast<std::size_t>(std::rand()) % n;
        const std::size_t i3 = static_cast<std::size_t>(std::rand()) % n;
        if (i1 == i2 || i1 == i3 || i2 == i3) continue;
        const Eigen::Vector4f &p1 = q[i1], &p2 = q[i2], &p3 = q[i3];
        Eigen::Vector4f v21 = p2 - p1, v31 = p3 - p1, v23 = p2 - p3;
        const float a = v21.norm(), b = v31.norm(), c = v23.norm();
        const float s = (a + b + c) * 0.5f;
        if (s * (s - a) * (s - b) * (s - c) <= 0.001f) continue;
        v21.normalize();
        v31.normalize();
        v23.normalize();
        const auto angle_bin = [&](const Eigen::Vector4f& u, const Eigen::Vector4f& v) {
            const float x = d::round_half_away(std::acos(std::abs(u.dot(v))) / half_pi * 63.0f);
            return std::isnan(x) ? -1 : static_cast<int>(x);
        };
        const int t1 = angle_bin(v21, v31), t2 = angle_bin(v23, v31), t3 = angle_bin(v23, v21);
        if (std::min({t1, t2, t3}) < 0 || std::max({t1, t2, t3}) > 63) continue;
        ++accepted;

        const auto distance = [](const Eigen::Vector4f& from, const Eigen::Vector4f& to) {
            const float x = to[0] - from[0], y = to[1] - from[1], z = to[2] - from[2];
            return std::sqrt(x * x + y * y + z * z);
        };
        const d::Line lines[3] = {d::trace(grid, cells[i1], cells[i2]),
                                  d::trace(grid, cells[i1], cells[i3]),
                                  d::trace(grid, cells[i2], cells[i3])};
        const float lengths[3] = {distance(p1, p2), distance(p1, p3), distance(p2, p3)};
        int occupied = 0, visited = 0;
        for (int k = 0; k < 3; ++k) {
            d2.push_back(lengths[k]);
            d2_kind.push_back(lines[k].kind);
            if (lines[k].kind == 2)
                h[kRatio][static_cast<std::size_t>(d::round_half_away(lines[k].ratio * 63.0f))] +=
                    1.0f;
            occupied += lines[k].occupied;
            visited += lines[k].visited;
        }
        d3.push_back(std::sqrt(std::sqrt(s * (s - a) * (s - b) * (s - c))));
        // The triangle's class; each angle weighted by the visited cells of the opposite line.
        int a3 = kA3Mixed;
        float weight = static_cast<float>(occupied) / static_cast<float>(visited);
        if (occupied <= 21) {
            a3 = kA3Out;
            weight = 0.0f;
        } else if (visited - occupied < 4) {
            a3 = kA3In;
            weight = 1.0f;
        }
        auto& block = h[static_cast<std::size_t>(a3)];
        block[static_cast<std::size_t>(t1)] += static_cast<float>(lines[2].visited) / 32.0f;
        block[static_cast<std::size_t>(t2)] += static_cast<float>(lines[0].visited) / 32.0f;
        block[static_cast<std::size_t>(t3)] += static_cast<float>(lines[1].visited) / 32.0f;
        d3_weight.push_back(weight);
    }

    const float max_d2 = *std::max_element(d2.begin(), d2.end());
    const float max_d3 = *std::max_element(d3.begin(), d3.end());
    for (std::size_t i = 0; i < d3.size(); ++i) {
        const int bin = static_cast<int>(d::round_half_away(d3[i] / max_d3 * 63.0f));
        if (bin < 0 || bin > 63) continue;
        const int block = d3_weight[i] >= 0.999f   ? kD3In
                          : d3_weight[i] <= 0.001f ? kD3Out
                                                   : kD3Mixed;
        h[static_cast<std::size_t>(block)][static_cast<std::size_t>(bin)] += 1.0f;
    }
    for (std::size_t i = 0; i < d2.size(); ++i) {
        const auto bin = static_cast<std::size_t>(d::round_half_away(d2[i] / max_d2 * 63.0f));
        h[static_cast<std::size_t>(kD2In + d2_kind[i])][bin] += 1.0f;
    }

    const float weights[10] = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 1.0f, 0.5f, 2.0f, 2.0f, 1.0f};
    EsfDescriptor out{};
    float sum = 0.0f;
    for (std::size_t b = 0; b < 10; ++b)
        for (std::size_t i = 0; i < 64; ++i) {
            out[b * 64 + i] = h[b][i] * weights[b];
            sum += out[b * 64 + i];
        }
    for (float& v : out) v /= sum;
    return out;
}

}  // namespace esf::test
