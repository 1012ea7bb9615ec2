#include "segmentation/euclidean_clusters.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/disjoint_sets.hpp"

namespace esf::detail {

namespace {

constexpr int kKeyBits = 21;
constexpr std::int64_t kKeyOffset = std::int64_t{1} << (kKeyBits - 1);
constexpr std::uint64_t kEmptyKey = ~std::uint64_t{0};
// Neighbour cells are searched up to this many cells away per axis.
constexpr std::int64_t kReach = 2;

/// Open-addressing map from packed grid keys to dense ids (first come, first numbered).
class KeyMap {
  public:
    explicit KeyMap(std::size_t expected) {
        std::size_t capacity = 16;
        while (capacity < 2 * expected) capacity *= 2;
        keys_.assign(capacity, kEmptyKey);
        ids_.resize(capacity);
        mask_ = capacity - 1;
    }

    /// The id of `key`, inserting it with id `next` when new (then `inserted` is true).
    std::uint32_t insert(std::uint64_t key, std::uint32_t next, bool& inserted) {
        std::size_t slot = hash(key);
        while (keys_[slot] != kEmptyKey) {
            if (keys_[slot] == key) {
                inserted = false;
                return ids_[slot];
            }
            slot = (slot + 1) & mask_;
        }
        keys_[slot] = key;
        ids_[slot] = next;
        inserted = true;
        return next;
    }

    /// The id of `key`, or -1.
    std::int64_t find(std::uint64_t key) const {
        std::size_t slot = hash(key);
        while (keys_[slot] != kEmptyKey) {
            if (keys_[slot] == key) return ids_[slot];
            slot = (slot + 1) & mask_;
        }
        return -1;
    }

  private:
    std::size_t hash(std::uint64_t key) const {
        return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 32) & mask_;
    }

    std::vector<std::uint64_t> keys_;
    std::vector<std::uint32_t> ids_;
    std::size_t mask_ = 0;
};

struct Cell {
    std::int64_t x, y, z;
};

Cell cell_of(const Eigen::Vector3f& p, float side) {
    return {static_cast<std::int64_t>(std::floor(p.x() / side)),
            static_cast<std::int64_t>(std::floor(p.y() / side)),
            static_cast<std::int64_t>(std::floor(p.z() / side))};
}

bool cell_fits(const Cell& c) {
    constexpr std::int64_t lo = -kKeyOffset + kReach, hi = kKeyOffset - 1 - kReach;
    return c.x >= lo && c.x <= hi && c.y >= lo && c.y <= hi && c.z >= lo && c.z <= hi;
}

std::uint64_t pack(const Cell& c) {
    return (static_cast<std::uint64_t>(c.x + kKeyOffset) << (2 * kKeyBits)) |
           (static_cast<std::uint64_t>(c.y + kKeyOffset) << kKeyBits) |
           static_cast<std::uint64_t>(c.z + kKeyOffset);
}

/// Cell side for a tolerance: the cell diagonal stays below the tolerance.
float cell_side(float tolerance) { return tolerance / std::sqrt(3.0f) * (1.0f - 1e-5f); }

}  // namespace

bool fits_clustering_grid(const Eigen::Vector3f& p, float tolerance) {
    return cell_fits(cell_of(p, cell_side(tolerance)));
}

/// Connected components of the graph linking points at most `tolerance` apart: exactly the
/// clusters of PCL's EuclideanClusterExtraction (Rusu 2009, Sec. 4.2), without a k-d tree.
/// The grid's cells have a diagonal below the tolerance, so the points of one cell are always
/// one component (the grid DBSCAN idea of Gunawan 2013); two cells up to kReach apart per
/// axis are linked when any pair of their points is close enough (bounding boxes first).
/// Returns the component of each point, numbered in order of first appearance.
std::vector<std::uint32_t> euclidean_components(std::span<const Eigen::Vector3f> points,
                                                float tolerance) {
    const std::size_t n = points.size();
    const float side = cell_side(tolerance);
    KeyMap map(n);
    std::vector<std::uint32_t> cell_of_point(n);
    std::vector<Cell> cells;
    for (std::size_t i = 0; i < n; ++i) {
        const Cell c = cell_of(points[i], side);
        bool inserted = false;
        cell_of_point[i] = map.insert(pack(c), static_cast<std::uint32_t>(cells.size()), inserted);
        if (inserted) cells.push_back(c);
    }
    const std::size_t cell_count = cells.size();
    // Points of each cell in compressed rows, and the cell's bounding box.
    std::vector<std::uint32_t> start(cell_count + 1, 0);
    for (std::uint32_t c : cell_of_point) ++start[c + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<Eigen::Vector3f> sorted(n);
    std::vector<Eigen::Vector3f> low(
        cell_count, Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity()));
    std::vector<Eigen::Vector3f> high(cell_count, -low.front());
    {
        std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint32_t c = cell_of_point[i];
            sorted[fill[c]++] = points[i];
            low[c] = low[c].cwiseMin(points[i]);
            high[c] = high[c].cwiseMax(points[i]);
        }
    }
    // Half of the neighbourhood: each pair of cells is examined once.
    std::vector<Cell> offsets;
    for (std::int64_t dx = -kReach; dx <= kReach; ++dx)
        for (std::int64_t dy = -kReach; dy <= kReach; ++dy)
            for (std::int64_t dz = -kReach; dz <= kReach; ++dz)
                if (dx > 0 || (dx == 0 && (dy > 0 || (dy == 0 && dz > 0))))
                    offsets.push_back({dx, dy, dz});

    std::stable_sort(offsets.begin(), offsets.end(), [](const Cell& a, const Cell& b) {
        return a.x * a.x + a.y * a.y + a.z * a.z < b.x * b.x + b.y * b.y + b.z * b.z;
    });

    const float t2 = tolerance * tolerance;
    auto near_box = [&](const Eigen::Vector3f& p, std::uint32_t cell) {
        return (low[cell] - p).cwiseMax(p - high[cell]).cwiseMax(0.0f).squaredNorm() <= t2;
    };
    std::vector<Eigen::Vector3f> near_a;  // the points of cell b that can reach cell a
    auto linked = [&](std::uint32_t a, std::uint32_t b) {
        const Eigen::Vector3f gap =
            (low[b] - high[a]).cwiseMax(low[a] - high[b]).cwiseMax(Eigen::Vector3f::Zero());
        if (gap.squaredNorm() > t2) return false;
        near_a.clear();
        for (std::uint32_t j = start[b]; j < start[b + 1]; ++j)
            if (near_box(sorted[j], a)) near_a.push_back(sorted[j]);
        for (std::uint32_t i = start[a]; i < start[a + 1]; ++i) {
            if (!near_box(sorted[i], b)) continue;
            for (const Eigen::Vector3f& q : near_a)
                if ((sorted[i] - q).squaredNorm() <= t2) return true;
        }
        return false;
    };
    // Pairs of cells already in one component need no test; nearer neighbours go first.
    DisjointSets sets(cell_count);
    for (std::uint32_t a = 0; a < cell_count; ++a) {
        const Cell& c = cells[a];
        for (const Cell& o : offsets) {
            const std::int64_t found = map.find(pack({c.x + o.x, c.y + o.y, c.z + o.z}));
            if (found < 0) continue;
            const auto b = static_cast<std::uint32_t>(found);
            if (sets.find(a) != sets.find(b) && linked(a, b)) sets.unite(a, b);
        }
    }
    sets.number_sets(cell_of_point);
    return cell_of_point;
}

}  // namespace esf::detail
