#include "esf/segmentation/surface_patches.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "core/disjoint_sets.hpp"
#include "core/pixel_rows.hpp"

namespace esf {

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

/// Running sums of a patch's points, relative to its first point (for numerical stability).
struct PatchSums {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
    std::uint32_t count = 0;

    void add(const Eigen::Vector3f& p) {
        const Eigen::Vector3d q = p.cast<double>();
        if (count == 0) origin = q;
        const Eigen::Vector3d d = q - origin;
        sum += d;
        outer += d * d.transpose();
        ++count;
    }
};

SurfacePatch finish(const PatchSums& s, const SurfacePatchOptions& options) {
    SurfacePatch patch;
    patch.points = s.count;
    const Eigen::Vector3d mean = s.sum / static_cast<double>(s.count);
    patch.centroid = (s.origin + mean).cast<float>();
    if (s.count < options.min_normal_points) return patch;
    const Eigen::Matrix3d covariance =
        s.outer / static_cast<double>(s.count) - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(covariance);
    const Eigen::Vector3d& values = solver.eigenvalues();  // ascending
    // Collinear (or a single repeated point): no plane.
    if (!(values[1] > 1e-3 * values[2]) || !(values[2] > 0.0)) return patch;
    Eigen::Vector3f normal = solver.eigenvectors().col(0).cast<float>().normalized();
    if (!normal.allFinite()) return patch;
    if (normal.dot(options.viewpoint - patch.centroid) < 0.0f) normal = -normal;
    patch.normal = normal;
    return patch;
}

/// Sorted unique edges from packed (a << 32 | b) pairs, counting repeats as contacts.
std::vector<PatchEdge> count_edges(std::vector<std::uint64_t>& pairs) {
    std::sort(pairs.begin(), pairs.end());
    std::vector<PatchEdge> edges;
    for (std::size_t i = 0; i < pairs.size();) {
        std::size_t j = i;
        while (j < pairs.size() && pairs[j] == pairs[i]) ++j;
        edges.push_back({static_cast<std::uint32_t>(pairs[i] >> 32),
                         static_cast<std::uint32_t>(pairs[i] & 0xFFFFFFFFu),
                         static_cast<std::uint32_t>(j - i)});
        i = j;
    }
    return edges;
}

std::uint64_t pair_key(std::uint32_t a, std::uint32_t b) {
    if (a > b) std::swap(a, b);
    return (static_cast<std::uint64_t>(a) << 32) | b;
}

/// Patch ids numbered in order of the first member of each set; sums and patches filled.
PatchGraph number_patches(std::span<const Eigen::Vector3f> points,
                          std::span<const std::uint32_t> members, DisjointSets& sets,
                          const SurfacePatchOptions& options) {
    PatchGraph graph;
    graph.patch_of.resize(members.size());
    std::vector<std::uint32_t> id_of_root(members.size(), kNone);
    std::vector<PatchSums> sums;
    for (std::uint32_t m = 0; m < members.size(); ++m) {
        const std::uint32_t root = sets.find(m);
        if (id_of_root[root] == kNone) {
            id_of_root[root] = static_cast<std::uint32_t>(sums.size());
            sums.emplace_back();
        }
        graph.patch_of[m] = id_of_root[root];
        sums[id_of_root[root]].add(points[members[m]]);
    }
    graph.patches.reserve(sums.size());
    for (const PatchSums& s : sums) graph.patches.push_back(finish(s, options));
    return graph;
}

}  // namespace

void validate(const SurfacePatchOptions& o) {
    auto fail = [](const std::string& what) {
        throw std::invalid_argument("surface patch options: " + what);
    };
    if (o.tile_pixels < 2 || o.tile_pixels > 1024)
        fail("tile_pixels must be in [2, 1024], got " + std::to_string(o.tile_pixels));
    if (!(o.voxel_size > 0.0f) || !std::isfinite(o.voxel_size))
        fail("voxel_size must be positive and finite, got " + std::to_string(o.voxel_size));
    if (!(o.depth_jump >= 0.0f) || !std::isfinite(o.depth_jump))
        fail("depth_jump must be >= 0 and finite, got " + std::to_string(o.depth_jump));
    if (!(o.depth_jump_quadratic >= 0.0f) || !std::isfinite(o.depth_jump_quadratic))
        fail("depth_jump_quadratic must be >= 0 and finite, got " +
             std::to_string(o.depth_jump_quadratic));
    if (o.min_normal_points < 3)
        fail("min_normal_points must be >= 3, got " + std::to_string(o.min_normal_points));
    if (!o.viewpoint.allFinite()) fail("the viewpoint must be finite");
}

PatchGraph image_patches(std::span<const Eigen::Vector3f> points, std::uint32_t width,
                         std::uint32_t height, std::span<const std::uint32_t> members,
                         const SurfacePatchOptions& options) {
    validate(options);
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    if (points.size() != pixels)
        throw std::invalid_argument("image_patches: " + std::to_string(points.size()) +
                                    " points for a " + std::to_string(width) + " x " +
                                    std::to_string(height) + " image");
    std::vector<std::uint32_t> member_at(pixels, kNone);
    std::vector<float> range(members.size());
    for (std::uint32_t m = 0; m < members.size(); ++m) {
        if (members[m] >= pixels || (m > 0 && members[m] <= members[m - 1]))
            throw std::invalid_argument(
                "image_patches: members must be ascending pixel indices below " +
                std::to_string(pixels));
        member_at[members[m]] = m;
        range[m] = (points[members[m]] - options.viewpoint).norm();
    }
    auto continuous = [&](std::uint32_t a, std::uint32_t b) {
        const float r = std::min(range[a], range[b]);
        return std::abs(range[a] - range[b]) <=
               options.depth_jump + options.depth_jump_quadratic * r * r;
    };
    const std::uint32_t tile = options.tile_pixels;

    // Patches: depth-continuous pixels of one tile. Whether a column or row is a tile's last.
    std::vector<std::uint8_t> last_col(width), last_row(height);
    for (std::uint32_t c = 0; c < width; ++c) last_col[c] = (c + 1) % tile == 0;
    for (std::uint32_t r = 0; r < height; ++r) last_row[r] = (r + 1) % tile == 0;
    DisjointSets sets(members.size());
    detail::PixelRows rows(width);
    for (std::uint32_t m = 0; m < members.size(); ++m) {
        const std::uint32_t pixel = members[m];
        rows.seek(pixel);
        const std::uint32_t row = rows.row(), col = rows.col();
        if (col + 1 < width && !last_col[col]) {
            const std::uint32_t right = member_at[pixel + 1];
            if (right != kNone && continuous(m, right)) sets.unite(m, right);
        }
        if (row + 1 < height && !last_row[row]) {
            const std::uint32_t down = member_at[pixel + width];
            if (down != kNone && continuous(m, down)) sets.unite(m, down);
        }
    }
    PatchGraph graph = number_patches(points, members, sets, options);

    // Adjacency: depth-continuous 4-neighbours in different patches.
    std::vector<std::uint64_t> pairs;
    for (std::uint32_t m = 0; m < members.size(); ++m) {
        const std::uint32_t pixel = members[m];
        rows.seek(pixel);
        const std::uint32_t row = rows.row(), col = rows.col();
        const std::uint32_t neighbours[2] = {col + 1 < width ? member_at[pixel + 1] : kNone,
                                             row + 1 < height ? member_at[pixel + width] : kNone};
        for (const std::uint32_t n : neighbours)
            if (n != kNone && graph.patch_of[n] != graph.patch_of[m] && continuous(m, n))
                pairs.push_back(pair_key(graph.patch_of[m], graph.patch_of[n]));
    }
    graph.edges = count_edges(pairs);
    return graph;
}

PatchGraph voxel_patches(std::span<const Eigen::Vector3f> points,
                         std::span<const std::uint32_t> members,
                         const SurfacePatchOptions& options) {
    validate(options);
    constexpr int kBits = 21;
    constexpr std::int64_t kOffset = std::int64_t{1} << (kBits - 1);
    auto cell = [&](const Eigen::Vector3f& p) {
        Eigen::Matrix<std::int64_t, 3, 1> c;
        for (int k = 0; k < 3; ++k) {
            const double v = std::floor(static_cast<double>(p[k]) / options.voxel_size);
            if (!(v > static_cast<double>(-kOffset + 1) && v < static_cast<double>(kOffset - 2)))
                throw std::invalid_argument(
                    "voxel_patches: coordinates too large for the voxel grid (at most 2^20 "
                    "voxels of voxel_size from the origin per axis)");
            c[k] = static_cast<std::int64_t>(v);
        }
        return c;
    };
    auto pack = [](const Eigen::Matrix<std::int64_t, 3, 1>& c) {
        return (static_cast<std::uint64_t>(c.x() + kOffset) << (2 * kBits)) |
               (static_cast<std::uint64_t>(c.y() + kOffset) << kBits) |
               static_cast<std::uint64_t>(c.z() + kOffset);
    };
    std::unordered_map<std::uint64_t, std::uint32_t> first_member;
    first_member.reserve(members.size());
    DisjointSets sets(members.size());
    std::vector<Eigen::Matrix<std::int64_t, 3, 1>> cells;
    std::vector<std::uint64_t> keys;
    for (std::uint32_t m = 0; m < members.size(); ++m) {
        if (members[m] >= points.size())
            throw std::invalid_argument("voxel_patches: member index out of range");
        const auto c = cell(points[members[m]]);
        const auto [it, inserted] = first_member.try_emplace(pack(c), m);
        if (inserted) {
            cells.push_back(c);
            keys.push_back(pack(c));
        } else {
            sets.unite(it->second, m);
        }
    }
    PatchGraph graph = number_patches(points, members, sets, options);

    std::vector<std::uint64_t> pairs;
    for (std::size_t v = 0; v < cells.size(); ++v) {
        const std::uint32_t a = graph.patch_of[first_member.at(keys[v])];
        for (std::int64_t dx = -1; dx <= 1; ++dx)
            for (std::int64_t dy = -1; dy <= 1; ++dy)
                for (std::int64_t dz = -1; dz <= 1; ++dz) {
                    if (!(dx > 0 || (dx == 0 && (dy > 0 || (dy == 0 && dz > 0))))) continue;
                    const Eigen::Matrix<std::int64_t, 3, 1> n =
                        cells[v] + Eigen::Matrix<std::int64_t, 3, 1>(dx, dy, dz);
                    const auto found = first_member.find(pack(n));
                    if (found == first_member.end()) continue;
                    pairs.push_back(pair_key(a, graph.patch_of[found->second]));
                }
    }
    graph.edges = count_edges(pairs);
    return graph;
}

}  // namespace esf
