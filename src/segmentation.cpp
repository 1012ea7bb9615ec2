#include "esf/segmentation.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "container_parts.hpp"
#include "disjoint_sets.hpp"
#include "esf/parallel.hpp"
#include "occluded_parts.hpp"
#include "splitmix64.hpp"

namespace esf {

namespace {

using Vec2 = Eigen::Vector2f;

// Fixed work split (independent of the thread count), so reductions add up in the same order.
constexpr std::size_t kChunks = 64;
// RANSAC hypotheses scored between two checks of the stopping rule.
constexpr std::size_t kHypothesisBatch = 32;
// Pixels from the image border within which a cluster may be cut off.
constexpr std::uint32_t kBorderMargin = 2;

std::string format_metres(double value) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.3g m", value);
    return buffer;
}

// One generator per RANSAC hypothesis, seeded from (seed, hypothesis index), so results never
// depend on the scheduling.
detail::SplitMix64 hypothesis_generator(std::uint64_t seed, std::uint64_t index) {
    return detail::SplitMix64(seed ^ (index * 0xD1B54A32D192ED03ull + 0x8CB92BA72F3D8DD7ull));
}

std::size_t chunk_begin(std::size_t chunk, std::size_t count) { return chunk * count / kChunks; }

// ---------------------------------------------------------------------------------------------
// Plane fit

struct Hypothesis {
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();
    float d = 0.0f;
    std::size_t inliers = 0;  // 0 for a degenerate sample
};

Hypothesis plane_hypothesis(std::span<const Eigen::Vector3f> samples, std::uint64_t seed,
                            std::size_t index, float distance) {
    detail::SplitMix64 rng = hypothesis_generator(seed, index);
    const std::size_t m = samples.size();
    const std::size_t i0 = rng.below(m);
    std::size_t i1 = rng.below(m);
    std::size_t i2 = rng.below(m);
    for (int retry = 0; retry < 8 && (i1 == i0 || i2 == i0 || i2 == i1); ++retry) {
        if (i1 == i0) i1 = rng.below(m);
        if (i2 == i0 || i2 == i1) i2 = rng.below(m);
    }
    Hypothesis h;
    if (i1 == i0 || i2 == i0 || i2 == i1) return h;
    const Eigen::Vector3f a = samples[i0];
    const Eigen::Vector3f ab = samples[i1] - a;
    const Eigen::Vector3f ac = samples[i2] - a;
    const Eigen::Vector3f n = ab.cross(ac);
    const float n_norm = n.norm();
    // Nearly collinear samples give no plane (sine of the angle below 1e-4).
    if (!(n_norm > 1e-4f * ab.norm() * ac.norm())) return h;
    h.normal = n / n_norm;
    h.d = -h.normal.dot(a);
    std::size_t count = 0;
    const float nx = h.normal.x(), ny = h.normal.y(), nz = h.normal.z(), d = h.d;
    for (const Eigen::Vector3f& p : samples)
        count += std::abs(nx * p.x() + ny * p.y() + nz * p.z() + d) <= distance ? 1 : 0;
    h.inliers = count;
    return h;
}

/// RANSAC (Fischler & Bolles 1981) with the usual adaptive stopping rule: stop after
/// log(1 - confidence) / log(1 - w^3) hypotheses, w the best inlier ratio so far.
Hypothesis ransac_plane(std::span<const Eigen::Vector3f> samples,
                        const SegmentationOptions& options) {
    Hypothesis best;
    if (samples.size() < 3) return best;
    const std::size_t max_hypotheses = static_cast<std::size_t>(options.plane_iterations);
    std::vector<Hypothesis> batch(kHypothesisBatch);
    std::size_t done = 0;
    double needed = static_cast<double>(max_hypotheses);
    while (done < max_hypotheses && static_cast<double>(done) < needed) {
        const std::size_t count = std::min(kHypothesisBatch, max_hypotheses - done);
        parallel_for(count, options.threads, [&](std::size_t i) {
            batch[i] = plane_hypothesis(samples, options.seed, done + i, options.plane_distance);
        });
        for (std::size_t i = 0; i < count; ++i)
            if (batch[i].inliers > best.inliers) best = batch[i];
        done += count;
        const double w = static_cast<double>(best.inliers) / static_cast<double>(samples.size());
        const double w3 = w * w * w;
        if (w3 >= 1.0) break;
        if (w3 > 0.0) needed = std::log(1.0 - options.plane_confidence) / std::log1p(-w3);
    }
    return best;
}

/// Least-squares plane through the points within `distance` of `plane` (normal = eigenvector
/// of the smallest eigenvalue of their covariance). Returns the input plane when fewer than 3.
Plane refit_plane(std::span<const Eigen::Vector3f> points, const Plane& plane, float distance) {
    // Centre on a point of the plane to keep the second moments well conditioned.
    const Eigen::Vector3d origin = (-plane.d * plane.normal).cast<double>();
    std::size_t count = 0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3f& p : points) {
        if (std::abs(plane.height(p)) > distance) continue;
        const Eigen::Vector3d q = p.cast<double>() - origin;
        ++count;
        sum += q;
        outer.noalias() += q * q.transpose();
    }
    if (count < 3) return plane;
    const double n = static_cast<double>(count);
    const Eigen::Vector3d mean = sum / n;
    const Eigen::Matrix3d covariance = outer / n - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    Eigen::Vector3d normal = solver.eigenvectors().col(0);
    if (!normal.allFinite() || normal.norm() < 0.5) return plane;
    normal.normalize();
    if (normal.dot(plane.normal.cast<double>()) < 0.0) normal = -normal;
    Plane refined;
    refined.normal = normal.cast<float>();
    refined.d = static_cast<float>(-normal.dot(mean + origin));
    return refined;
}

// ---------------------------------------------------------------------------------------------
// 2-D convex hulls

double cross(const Vec2& o, const Vec2& a, const Vec2& b) {
    return (static_cast<double>(a.x()) - o.x()) * (static_cast<double>(b.y()) - o.y()) -
           (static_cast<double>(a.y()) - o.y()) * (static_cast<double>(b.x()) - o.x());
}

/// The extreme points of a point set in eight directions. No point strictly inside their
/// polygon can be a vertex of the convex hull (Akl & Toussaint 1978), which leaves few points
/// to sort. Octagons of parts of a set merge into the octagon of the whole.
class Octagon {
  public:
    void add(const Vec2& p) {
        for (int k = 0; k < 8; ++k) {
            const float v = kDirections[k][0] * p.x() + kDirections[k][1] * p.y();
            if (v > best_[k]) {
                best_[k] = v;
                point_[k] = p;
            }
        }
    }

    void merge(const Octagon& other) {
        for (int k = 0; k < 8; ++k)
            if (other.best_[k] > best_[k]) {
                best_[k] = other.best_[k];
                point_[k] = other.point_[k];
            }
    }

    /// Appends the points of `points` that are not strictly inside the octagon to `out`.
    void append_outside(std::span<const Vec2> points, std::vector<Vec2>& out) const {
        // Edges as lines a x + b y + c = 0, positive inside (the polygon is counter-clockwise).
        std::array<std::array<double, 3>, 8> lines{};
        std::size_t count = 0;
        std::array<Vec2, 8> polygon;
        std::size_t vertices = 0;
        for (int k = 0; k < 8; ++k) {
            if (!(best_[k] > -std::numeric_limits<float>::infinity())) {
                out.insert(out.end(), points.begin(), points.end());
                return;
            }
            if (vertices == 0 || polygon[vertices - 1] != point_[k])
                polygon[vertices++] = point_[k];
        }
        while (vertices > 1 && polygon[0] == polygon[vertices - 1]) --vertices;
        if (vertices < 3) {
            out.insert(out.end(), points.begin(), points.end());
            return;
        }
        for (std::size_t k = 0; k < vertices; ++k) {
            const Vec2& p = polygon[k];
            const Vec2& q = polygon[(k + 1) % vertices];
            const double a = static_cast<double>(p.y()) - q.y();
            const double b = static_cast<double>(q.x()) - p.x();
            lines[count++] = {a, b, -(a * p.x() + b * p.y())};
        }
        for (const Vec2& p : points) {
            bool inside = true;
            for (std::size_t k = 0; k < count && inside; ++k)
                inside = lines[k][0] * p.x() + lines[k][1] * p.y() + lines[k][2] > 0.0;
            if (!inside) out.push_back(p);
        }
    }

  private:
    // Counter-clockwise: +x, +x+y, +y, -x+y, -x, -x-y, -y, +x-y.
    static constexpr float kDirections[8][2] = {{1, 0},  {1, 1},   {0, 1},  {-1, 1},
                                                {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
    std::array<float, 8> best_ = {
        -std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
        -std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
        -std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
        -std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()};
    std::array<Vec2, 8> point_{};
};

/// Andrew's monotone chain: the convex hull counter-clockwise, without collinear vertices.
std::vector<Vec2> monotone_chain(std::vector<Vec2> points) {
    std::sort(points.begin(), points.end(), [](const Vec2& a, const Vec2& b) {
        return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
    points.erase(std::unique(points.begin(), points.end()), points.end());
    if (points.size() < 3) return points;
    std::vector<Vec2> hull(2 * points.size());
    std::size_t k = 0;
    for (const Vec2& p : points) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], p) <= 0.0) --k;
        hull[k++] = p;
    }
    for (std::size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
        hull[k++] = points[i];
    }
    hull.resize(k - 1);
    return hull;
}

std::vector<Vec2> convex_hull(std::span<const Vec2> points) {
    Octagon octagon;
    for (const Vec2& p : points) octagon.add(p);
    std::vector<Vec2> candidates;
    octagon.append_outside(points, candidates);
    return monotone_chain(std::move(candidates));
}

/// Point in a convex counter-clockwise polygon (boundary counts as inside), O(log n).
bool inside_convex(std::span<const Vec2> hull, const Vec2& q) {
    const std::size_t n = hull.size();
    if (cross(hull[0], hull[1], q) < 0.0 || cross(hull[0], hull[n - 1], q) > 0.0) return false;
    std::size_t lo = 1, hi = n - 1;  // find the wedge hull[0], hull[lo], hull[lo + 1]
    while (hi - lo > 1) {
        const std::size_t mid = (lo + hi) / 2;
        if (cross(hull[0], hull[mid], q) >= 0.0)
            lo = mid;
        else
            hi = mid;
    }
    return cross(hull[lo], hull[lo + 1], q) >= 0.0;
}

struct Rectangle {
    float length = 0.0f, width = 0.0f;
    Vec2 length_axis = Vec2::UnitX();
};

/// Smallest-area rectangle holding a strictly convex counter-clockwise polygon: one side lies
/// on a hull edge (Freeman & Shapira 1975); rotating calipers (Toussaint 1983) find the extreme
/// vertices of every edge in O(n) overall.
Rectangle min_area_rectangle(std::span<const Vec2> hull) {
    Rectangle best;
    const std::size_t n = hull.size();
    if (n == 2) {
        const Vec2 e = hull[1] - hull[0];
        best.length = e.norm();
        if (best.length > 0.0f) best.length_axis = e / best.length;
        return best;
    }
    if (n < 3) return best;
    auto at = [&](std::size_t i) -> Eigen::Vector2d { return hull[i % n].cast<double>(); };
    auto step = [&](std::size_t i) -> Eigen::Vector2d { return at(i + 1) - at(i); };
    double best_area = std::numeric_limits<double>::infinity();
    std::size_t far = 0, top = 0, near = 0;  // extreme along the edge, from it, against it
    bool first = true;
    for (std::size_t i = 0; i < n; ++i) {
        Eigen::Vector2d e = step(i);
        const double e_norm = e.norm();
        if (e_norm == 0.0) continue;
        e /= e_norm;
        const Eigen::Vector2d inward(-e.y(), e.x());
        if (first) far = i + 1;
        for (std::size_t guard = 0; guard < n && step(far).dot(e) > 0.0; ++guard) ++far;
        if (first) top = far;
        for (std::size_t guard = 0; guard < n && step(top).dot(inward) > 0.0; ++guard) ++top;
        if (first) near = top;
        for (std::size_t guard = 0; guard < n && step(near).dot(e) < 0.0; ++guard) ++near;
        first = false;
        const double la = (at(far) - at(near)).dot(e);
        const double lb = (at(top) - at(i)).dot(inward);
        if (la * lb < best_area) {
            best_area = la * lb;
            best.length = static_cast<float>(std::max(la, lb));
            best.width = static_cast<float>(std::min(la, lb));
            best.length_axis = (la >= lb ? e : inward).cast<float>();
        }
    }
    return best;
}

// ---------------------------------------------------------------------------------------------
// Euclidean clustering on a hash grid

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

// ---------------------------------------------------------------------------------------------

/// Orthonormal basis (u, w) of the plane with u x w = normal.
std::pair<Eigen::Vector3f, Eigen::Vector3f> plane_basis(const Eigen::Vector3f& normal) {
    const Eigen::Vector3f helper =
        std::abs(normal.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
    const Eigen::Vector3f u = normal.cross(helper).normalized();
    const Eigen::Vector3f w = normal.cross(u);
    return {u, w};
}

SegmentationResult segment(std::span<const Eigen::Vector3f> points, std::uint32_t width,
                           std::uint32_t height, const SegmentationOptions& options) {
    validate(options);
    if (points.empty()) throw std::invalid_argument("segment_scene: the cloud is empty");
    if (points.size() > std::numeric_limits<std::uint32_t>::max())
        throw std::invalid_argument("segment_scene: more than 2^32 - 1 points");
    const bool organised = height > 1 && static_cast<std::size_t>(width) * height == points.size();

    std::vector<std::uint32_t> finite;
    finite.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        if (points[i].allFinite()) finite.push_back(static_cast<std::uint32_t>(i));
    if (finite.empty())
        throw std::invalid_argument("segment_scene: the cloud has no finite points (" +
                                    std::to_string(points.size()) + " points, all NaN or inf)");

    SegmentationResult result;
    result.finite_points = finite.size();

    // 1. RANSAC on an even subsample.
    const std::size_t sample_count = std::min(finite.size(), options.plane_samples);
    std::vector<Eigen::Vector3f> samples(sample_count);
    for (std::size_t i = 0; i < sample_count; ++i)
        samples[i] = points[finite[i * finite.size() / sample_count]];
    const Hypothesis best = ransac_plane(samples, options);
    if (best.inliers == 0) {
        result.message = "no dominant plane: fewer than 3 non-collinear points";
        return result;
    }

    // 2. Least-squares refit to the sampled inliers; orient to the viewpoint.
    Plane plane{best.normal, best.d};
    plane = refit_plane(samples, plane, options.plane_distance);
    if (plane.height(options.viewpoint) < 0.0f) {
        plane.normal = -plane.normal;
        plane.d = -plane.d;
    }
    result.plane = plane;

    // 3./4. One pass: table points (projected, for the hull) and object candidates. In an
    // organised frame the table's hull needs only each image row's first and last table pixel:
    // the table lies in front of the camera, so the projection from the plane to the image
    // keeps convexity, and a pixel between two table pixels of its row is never a hull vertex.
    const auto [u, w] = plane_basis(plane.normal);
    struct Part {
        std::size_t table_points = 0;
        std::vector<Vec2> table;
        Octagon octagon;
        std::vector<Vec2> outside;
        std::vector<std::uint32_t> candidates;
    };
    std::vector<Part> parts(kChunks);
    parallel_for(kChunks, options.threads, [&](std::size_t c) {
        Part& part = parts[c];
        std::uint32_t row = std::numeric_limits<std::uint32_t>::max();
        std::uint32_t first = 0, last = 0;
        auto close_row = [&] {
            if (row == std::numeric_limits<std::uint32_t>::max()) return;
            part.outside.emplace_back(u.dot(points[first]), w.dot(points[first]));
            if (last != first) part.outside.emplace_back(u.dot(points[last]), w.dot(points[last]));
        };
        for (std::size_t k = chunk_begin(c, finite.size()); k < chunk_begin(c + 1, finite.size());
             ++k) {
            const Eigen::Vector3f& p = points[finite[k]];
            const float h = plane.height(p);
            if (std::abs(h) <= options.plane_distance) {
                ++part.table_points;
                if (organised) {
                    const std::uint32_t r = finite[k] / width;
                    if (r != row) {
                        close_row();
                        row = r;
                        first = finite[k];
                    }
                    last = finite[k];
                } else {
                    part.table.emplace_back(u.dot(p), w.dot(p));
                    part.octagon.add(part.table.back());
                }
            }
            if (h > options.min_height && h <= options.max_height)
                part.candidates.push_back(finite[k]);
        }
        close_row();
    });
    Octagon octagon;
    for (const Part& part : parts) {
        result.plane_inliers += part.table_points;
        octagon.merge(part.octagon);
    }
    const double needed_points =
        std::max(static_cast<double>(options.min_plane_points),
                 options.min_plane_fraction * static_cast<double>(finite.size()));
    if (static_cast<double>(result.plane_inliers) < needed_points) {
        result.message = "no dominant plane: the best plane holds " +
                         std::to_string(result.plane_inliers) + " of " +
                         std::to_string(finite.size()) + " finite points (needs " +
                         std::to_string(static_cast<std::size_t>(std::ceil(needed_points))) + ")";
        return result;
    }
    if (!organised)
        parallel_for(kChunks, options.threads, [&](std::size_t c) {
            octagon.append_outside(parts[c].table, parts[c].outside);
        });
    std::vector<Vec2> hull_candidates;
    std::vector<std::uint32_t> candidates;
    for (Part& part : parts) {
        hull_candidates.insert(hull_candidates.end(), part.outside.begin(), part.outside.end());
        candidates.insert(candidates.end(), part.candidates.begin(), part.candidates.end());
        part = Part{};
    }
    const std::vector<Vec2> hull = monotone_chain(std::move(hull_candidates));
    if (hull.size() < 3) {
        result.message = "no dominant plane: the plane's points are collinear";
        return result;
    }
    result.plane_found = true;

    // Keep the candidates whose projection lies inside the hull (the polygonal prism).
    std::vector<std::uint8_t> keep(candidates.size());
    parallel_for(kChunks, options.threads, [&](std::size_t c) {
        for (std::size_t k = chunk_begin(c, candidates.size());
             k < chunk_begin(c + 1, candidates.size()); ++k) {
            const Eigen::Vector3f& p = points[candidates[k]];
            keep[k] = inside_convex(hull, Vec2(u.dot(p), w.dot(p))) ? 1 : 0;
        }
    });
    std::size_t kept = 0;
    for (std::size_t k = 0; k < candidates.size(); ++k)
        if (keep[k]) candidates[kept++] = candidates[k];
    candidates.resize(kept);

    auto no_objects = [&](const std::string& why) {
        result.message = "no objects above the plane: " + why;
        return result;
    };
    if (candidates.empty())
        return no_objects("no points between " + format_metres(options.min_height) + " and " +
                          format_metres(options.max_height) + " above it inside its hull");

    // 5. Grouping of the candidates.
    std::vector<Eigen::Vector3f> candidate_points(candidates.size());
    for (std::size_t k = 0; k < candidates.size(); ++k) candidate_points[k] = points[candidates[k]];
    std::vector<std::uint32_t> component;
    if (options.grouping == Grouping::kConvexity) {
        SurfacePatchOptions patch_options = options.patches;
        patch_options.viewpoint = options.viewpoint;
        const PatchGraph graph =
            organised ? image_patches(points, width, height, candidates, patch_options)
                      : voxel_patches(points, candidates, patch_options);
        const std::vector<std::uint32_t> segment = convex_segments(graph, options.convexity);
        component.resize(candidates.size());
        for (std::size_t k = 0; k < candidates.size(); ++k)
            component[k] = segment[graph.patch_of[k]];
        if (organised && options.join_occluded_parts)
            detail::join_occluded_parts(points, width, height, candidates, component,
                                        options.viewpoint, plane.normal, plane.d);
        if (options.join_container_parts)
            detail::join_container_parts(candidate_points, component, plane.normal, plane.d);
    } else {
        const float side = cell_side(options.cluster_tolerance);
        for (const std::uint32_t i : candidates)
            if (!cell_fits(cell_of(points[i], side)))
                throw std::invalid_argument(
                    "segment_scene: coordinates too large for the clustering grid (point " +
                    std::to_string(i) +
                    "; at most 2^20 cells of cluster_tolerance / sqrt(3) from "
                    "the origin per axis)");
        component = euclidean_components(candidate_points, options.cluster_tolerance);
    }

    // 6. Clusters within the size limits.
    const std::uint32_t component_count = *std::max_element(component.begin(), component.end()) + 1;
    std::vector<std::size_t> component_points(component_count, 0);
    for (const std::uint32_t c : component) ++component_points[c];
    constexpr std::uint32_t kDropped = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> cluster_of(component_count, kDropped);
    std::uint32_t cluster_count = 0;
    for (std::uint32_t c = 0; c < component_count; ++c)
        if (component_points[c] >= options.min_cluster_points &&
            component_points[c] <= options.max_cluster_points)
            cluster_of[c] = cluster_count++;
    if (cluster_count == 0) {
        const std::size_t largest =
            *std::max_element(component_points.begin(), component_points.end());
        return no_objects(std::to_string(candidates.size()) + " points above it form " +
                          std::to_string(component_count) + " groups, the largest of " +
                          std::to_string(largest) + " points (clusters need " +
                          std::to_string(options.min_cluster_points) + " to " +
                          std::to_string(options.max_cluster_points) + ")");
    }
    std::vector<Cluster> clusters(cluster_count);
    for (std::uint32_t c = 0; c < component_count; ++c)
        if (cluster_of[c] != kDropped) {
            clusters[cluster_of[c]].indices.reserve(component_points[c]);
            clusters[cluster_of[c]].points.reserve(component_points[c]);
        }
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        const std::uint32_t cluster = cluster_of[component[k]];
        if (cluster == kDropped) continue;
        clusters[cluster].indices.push_back(candidates[k]);
        clusters[cluster].points.push_back(candidate_points[k]);
    }

    parallel_for(clusters.size(), options.threads, [&](std::size_t c) {
        Cluster& cluster = clusters[c];
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        float top = -std::numeric_limits<float>::infinity();
        std::vector<Vec2> projected;
        projected.reserve(cluster.points.size());
        for (const Eigen::Vector3f& p : cluster.points) {
            sum += p.cast<double>();
            top = std::max(top, plane.height(p));
            projected.emplace_back(u.dot(p), w.dot(p));
        }
        cluster.centroid = (sum / static_cast<double>(cluster.points.size())).cast<float>();
        const Rectangle box = min_area_rectangle(convex_hull(projected));
        cluster.size = Eigen::Vector3f(box.length, box.width, top);
        cluster.length_axis = (box.length_axis.x() * u + box.length_axis.y() * w).normalized();

        std::string why;
        if (organised) {
            for (const std::uint32_t i : cluster.indices) {
                const std::uint32_t row = i / width, col = i % width;
                if (row < kBorderMargin || col < kBorderMargin || row + kBorderMargin >= height ||
                    col + kBorderMargin >= width) {
                    why = "touches the image border";
                    break;
                }
            }
        }
        if (top >= options.max_height - options.cluster_tolerance) {
            if (!why.empty()) why += "; ";
            why += "reaches the height limit of " + format_metres(options.max_height);
        }
        if (!why.empty()) {
            cluster.status = ClusterStatus::kMaybeTruncated;
            cluster.message = "may be cut off: " + why;
        }
    });

    std::sort(clusters.begin(), clusters.end(), [](const Cluster& a, const Cluster& b) {
        if (a.points.size() != b.points.size()) return a.points.size() > b.points.size();
        for (int k = 0; k < 3; ++k)
            if (a.centroid[k] != b.centroid[k]) return a.centroid[k] < b.centroid[k];
        return a.indices.front() < b.indices.front();
    });
    result.clusters = std::move(clusters);
    result.message = std::to_string(result.clusters.size()) +
                     (result.clusters.size() == 1 ? " object" : " objects") + " above the plane";
    return result;
}

}  // namespace

void validate(const SegmentationOptions& o) {
    auto fail = [](const std::string& what) {
        throw std::invalid_argument("segmentation options: " + what);
    };
    auto positive = [&](float value, const char* name) {
        if (!(value > 0.0f) || !std::isfinite(value))
            fail(std::string(name) + " must be a positive length in metres, got " +
                 std::to_string(value));
    };
    positive(o.plane_distance, "plane_distance");
    positive(o.cluster_tolerance, "cluster_tolerance");
    positive(o.max_height, "max_height");
    if (o.plane_iterations < 1)
        fail("plane_iterations must be >= 1, got " + std::to_string(o.plane_iterations));
    if (o.plane_samples < 3)
        fail("plane_samples must be >= 3, got " + std::to_string(o.plane_samples));
    if (!(o.plane_confidence > 0.0 && o.plane_confidence < 1.0))
        fail("plane_confidence must be in (0, 1), got " + std::to_string(o.plane_confidence));
    if (!(o.min_plane_fraction >= 0.0 && o.min_plane_fraction <= 1.0))
        fail("min_plane_fraction must be in [0, 1], got " + std::to_string(o.min_plane_fraction));
    if (!std::isfinite(o.min_height) || o.min_height < 0.0f || o.min_height >= o.max_height)
        fail("min_height must be >= 0 and below max_height (" + std::to_string(o.max_height) +
             "), got " + std::to_string(o.min_height));
    if (o.min_cluster_points < 1) fail("min_cluster_points must be >= 1");
    if (o.max_cluster_points < o.min_cluster_points)
        fail("max_cluster_points (" + std::to_string(o.max_cluster_points) +
             ") is below min_cluster_points (" + std::to_string(o.min_cluster_points) + ")");
    if (!o.viewpoint.allFinite()) fail("viewpoint must be finite");
    if (o.threads < 0)
        fail("threads must be >= 0 (0 = all cores), got " + std::to_string(o.threads));
    if (o.grouping != Grouping::kConvexity && o.grouping != Grouping::kEuclidean)
        fail("unknown grouping");
    SurfacePatchOptions patches = o.patches;
    patches.viewpoint = o.viewpoint;
    validate(patches);
    validate(o.convexity);
}

SegmentationResult segment_scene(const PointCloud& cloud, const SegmentationOptions& options) {
    return segment(cloud.points, cloud.width, cloud.height, options);
}

SegmentationResult segment_scene(std::span<const Eigen::Vector3f> points,
                                 const SegmentationOptions& options) {
    return segment(points, static_cast<std::uint32_t>(points.size()), 1, options);
}

const char* to_string(ClusterStatus status) {
    switch (status) {
        case ClusterStatus::kOk:
            return "ok";
        case ClusterStatus::kMaybeTruncated:
            return "maybe_truncated";
    }
    return "unknown";
}

}  // namespace esf
