// The ESF descriptor's code paths: the SIMD kernels (AVX-512, AVX2) give the portable code's
// output bit for bit, on clouds chosen to reach their special cases; the triangle angles and
// ratios of the fast sampler; the finite-point filters.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "descriptors/esf/esf_points.hpp"
#include "descriptors/esf/esf_triangles.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "support/esf_clouds.hpp"

namespace {

using esf::test::esf_error_of;
using esf::test::partial_cylinder;
using ::testing::HasSubstr;

/// Descriptors and attempts of kAvx512, kAvx2 and kPortable against kBest's.
void expect_kernels_agree(const esf::Points& points, const esf::EsfOptions& best,
                          const std::string& what) {
    const auto a = esf::compute_esf(points, best);
    for (const esf::Kernels kernels :
         {esf::Kernels::kAvx512, esf::Kernels::kAvx2, esf::Kernels::kPortable}) {
        esf::EsfOptions other = best;
        other.kernels = kernels;
        const auto b = esf::compute_esf(points, other);
        EXPECT_EQ(a.descriptor, b.descriptor) << what << " " << to_string(kernels);
        EXPECT_EQ(a.attempts, b.attempts) << what << " " << to_string(kernels);
        EXPECT_EQ(a.dropped_points, b.dropped_points) << what << " " << to_string(kernels);
    }
}

TEST(EsfDescriptor, PortableCodeGivesTheSimdKernelsOutput) {
    const auto points = partial_cylinder(5000);
    for (std::uint64_t seed : {0u, 1u, 99u}) {
        esf::EsfOptions best;
        best.seed = seed;
        expect_kernels_agree(points, best, "seed " + std::to_string(seed));
    }
}

TEST(EsfDescriptor, PortableCodeGivesTheSimdKernelsOutputForOtherSizes) {
    // Point counts that leave partial blocks of 8 and 16 points; sample counts whose last block
    // of attempts is partial; grids other than 64.
    for (const std::size_t count : {std::size_t{37}, std::size_t{1000}, std::size_t{5003}})
        for (const int samples : {100, 1000, 1001, 20000})
            for (const int grid : {32, 40, 64}) {
                esf::EsfOptions best;
                best.samples = samples;
                best.grid_size = grid;
                best.seed = count + static_cast<std::size_t>(samples);
                expect_kernels_agree(partial_cylinder(count, 7), best,
                                     std::to_string(count) + " points, " + std::to_string(samples) +
                                         " samples, grid " + std::to_string(grid));
            }
}

TEST(EsfDescriptor, PortableCodeGivesTheSimdKernelsOutputWithNonFinitePoints) {
    esf::Points points = partial_cylinder(3001, 11);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    points[3] = {nan, 0, 0};
    points[40] = {0, -inf, 0};
    points.push_back({0, 0, inf});
    for (const int samples : {100, 1000, 20000}) {
        esf::EsfOptions best;
        best.samples = samples;
        expect_kernels_agree(points, best, std::to_string(samples) + " samples");
    }
}

// A scan in row order: runs of neighbouring points share a cell, which the AVX-512 kernel sets
// once per run (runs across its blocks of 16 included).
TEST(EsfDescriptor, KernelsAgreeOnCloudsInScanOrder) {
    esf::Points scan;
    for (int row = 0; row < 60; ++row)
        for (int column = 0; column < 157; ++column) {
            const float u = 0.004f * static_cast<float>(column),
                        v = 0.004f * static_cast<float>(row);
            scan.emplace_back(u, v, 0.3f * std::sin(4.0f * u) + 0.1f * v * v);
        }
    scan.insert(scan.begin() + 500, 40, scan[500]);  // a run of equal points
    esf::EsfOptions options;
    options.samples = 3000;
    expect_kernels_agree(scan, options, "scan");
}

// The voxel grid and packed points of every kernel against the portable code, for point orders
// with runs of one cell, alternating cells (A B A) and random cells, across blocks of 16.
TEST(EsfPoints, EveryKernelSetsTheSameGrid) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> coordinate(-1.0f, 1.0f);
    std::vector<std::pair<std::string, esf::Points>> clouds;
    esf::Points runs, alternating, random;
    for (int i = 0; i < 1000; ++i) {
        const Eigen::Vector3f a(coordinate(rng), coordinate(rng), coordinate(rng));
        const Eigen::Vector3f b(coordinate(rng), coordinate(rng), coordinate(rng));
        for (int k = 0; k < i % 7 + 1; ++k) runs.push_back(a);
        alternating.push_back(a);
        alternating.push_back(b);
        alternating.push_back(a);
        random.push_back(a);
    }
    clouds = {{"runs", runs}, {"alternating", alternating}, {"random", random}};
    namespace d = esf::detail;
    for (const auto& [name, points] : clouds) {
        d::Normalisation t;
        ASSERT_EQ(d::normalise_points(points, 32, d::SimdLevel::kPortable, t),
                  d::NormaliseOutcome::kNormalised);
        std::vector<d::PackedPoint> reference_packed;
        std::vector<std::uint32_t> cells;
        d::VoxelGrid reference;
        reference.clear();
        d::voxelise_points(points, t, 32, d::SimdLevel::kPortable, reference_packed, cells,
                           reference);
        for (const d::SimdLevel simd : {d::SimdLevel::kAvx512, d::SimdLevel::kAvx2}) {
            if (simd == d::SimdLevel::kAvx512 && !d::avx512_available()) continue;
            if (simd == d::SimdLevel::kAvx2 && !d::avx2_available()) continue;
            std::vector<d::PackedPoint> packed;
            d::VoxelGrid grid;
            grid.clear();
            d::voxelise_points(points, t, 32, simd, packed, cells, grid);
            EXPECT_TRUE(grid.words == reference.words) << name;
            ASSERT_EQ(packed.size(), reference_packed.size()) << name;
            EXPECT_EQ(0, std::memcmp(packed.data(), reference_packed.data(),
                                     packed.size() * sizeof(d::PackedPoint)))
                << name;
        }
    }
}

// The AVX-512 kernel answers "not on one line" from float sums when the cloud is clearly not a
// line; a thin rod (second eigenvalue about 1 % of the first) and a line with noise of 1e-7 of
// its length take its exact path. Every kernel must reach the same answer.
TEST(EsfDescriptor, KernelsAgreeOnThinRodsAndAlmostStraightLines) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> along(0.0f, 1.0f), across(-0.05f, 0.05f);
    esf::Points rod, line;
    for (int i = 0; i < 3000; ++i) {
        const float t = along(rng);
        rod.emplace_back(t, 0.3f * t + across(rng), -t + across(rng));
        line.emplace_back(t, 2.0f * t + 1e-7f * across(rng), 0.5f - t);
    }
    esf::EsfOptions options;
    options.samples = 2000;
    expect_kernels_agree(rod, options, "thin rod");
    for (const esf::Kernels kernels : {esf::Kernels::kBest, esf::Kernels::kAvx512,
                                       esf::Kernels::kAvx2, esf::Kernels::kPortable}) {
        options.kernels = kernels;
        EXPECT_THAT(esf_error_of(line, options), HasSubstr("lie on one line"))
            << to_string(kernels);
    }
}

TEST(EsfDescriptor, KernelsAgreeWhenTheAttemptsRunOut) {
    // Few points far from a line: many triples are degenerate, and the attempts run out.
    esf::Points points(40, Eigen::Vector3f::Zero());
    for (std::size_t i = 0; i < points.size(); ++i)
        points[i] = {static_cast<float>(i), 0.0f, i % 13 == 0 ? 1.0f : 0.0f};
    esf::EsfOptions options;
    options.samples = 1000;
    options.max_attempts_per_sample = 1;
    std::string first;
    for (const esf::Kernels kernels : {esf::Kernels::kBest, esf::Kernels::kAvx512,
                                       esf::Kernels::kAvx2, esf::Kernels::kPortable}) {
        options.kernels = kernels;
        const std::string error = esf_error_of(points, options);
        EXPECT_THAT(error, HasSubstr("non-degenerate triangles in 1000 random triples"));
        if (first.empty()) first = error;
        EXPECT_EQ(error, first) << to_string(kernels);
    }
}

TEST(EsfDescriptor, KernelNamesRoundTrip) {
    for (const esf::Kernels kernels :
         {esf::Kernels::kBest, esf::Kernels::kAvx512, esf::Kernels::kAvx2, esf::Kernels::kPortable})
        EXPECT_EQ(esf::parse_enum<esf::Kernels>(esf::to_string(kernels)), kernels);
    try {
        esf::parse_enum<esf::Kernels>("sse");
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "unknown kernels 'sse' (expected best, avx512, avx2 or portable)");
    }
}

}  // namespace

// The fast sampler's angles against acos of the angles themselves, on random triangles of every
// kind (acute, and obtuse at each corner).
TEST(EsfTriangles, AngleBinsFromSideLengthsMatchTheAngles) {
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> coordinate(-10.0f, 10.0f);
    const auto folded_bin = [](const Eigen::Vector3f& from, const Eigen::Vector3f& to1,
                               const Eigen::Vector3f& to2) {
        const Eigen::Vector3d u = (to1 - from).cast<double>(), v = (to2 - from).cast<double>();
        const double angle = std::acos(std::abs(u.dot(v)) / (u.norm() * v.norm()));
        return angle / (std::acos(-1.0) / 2) * 63;  // the bin position before rounding
    };
    int obtuse[3] = {0, 0, 0}, compared = 0;
    for (int t = 0; t < 20000; ++t) {
        Eigen::Vector3f p1, p2, p3;
        for (int k = 0; k < 3; ++k) {
            p1[k] = coordinate(rng), p2[k] = coordinate(rng), p3[k] = coordinate(rng);
        }
        const float a = (p2 - p1).norm(), b = (p3 - p1).norm(), c = (p2 - p3).norm();
        const float s = (a + b + c) / 2;
        if (s * (s - a) * (s - b) * (s - c) < 1.0f) continue;  // ESF rejects thin triangles
        const std::uint32_t bins = esf::detail::triangle_angle_bins(a, b, c);
        const double expected[3] = {folded_bin(p1, p2, p3), folded_bin(p3, p1, p2),
                                    folded_bin(p2, p1, p3)};  // at p1, p3, p2
        for (int k = 0; k < 3; ++k) {
            const double position = expected[k];
            if (std::abs(position - std::floor(position) - 0.5) < 1e-3) continue;  // a border
            ASSERT_EQ(static_cast<double>(bins >> (8 * k) & 255), std::floor(position + 0.5))
                << "triangle " << t << ", angle " << k;
            ++compared;
        }
        obtuse[0] += (p2 - p1).dot(p3 - p1) < 0;
        obtuse[1] += (p1 - p3).dot(p2 - p3) < 0;
        obtuse[2] += (p1 - p2).dot(p3 - p2) < 0;
    }
    EXPECT_GT(compared, 20000);
    for (int corner : obtuse) EXPECT_GT(corner, 100);  // every branch of third_angle() was taken
}

TEST(EsfTriangles, AngleBinsRoundToTheNearestOf64) {
    const double bin_width = std::acos(-1.0) / 2 / 63;
    for (int bin = 0; bin < 64; ++bin) {
        EXPECT_EQ(esf::detail::angle_bin(static_cast<float>(bin * bin_width)), bin);
        EXPECT_EQ(esf::detail::angle_bin(static_cast<float>((bin + 0.45) * bin_width)), bin);
        if (bin > 0) {
            EXPECT_EQ(esf::detail::angle_bin(static_cast<float>((bin - 0.45) * bin_width)), bin);
        }
    }
    EXPECT_EQ(esf::detail::angle_bin(-1e-6f), 0);  // a difference of angles a hair below zero
    EXPECT_EQ(esf::detail::angle_bin(2.0f), 63);
}

// The AVX-512 histogram forms a line's occupied / visited ratio without a division: it must be
// the rounded quotient for every count a line can have.
TEST(EsfTriangles, RatiosWithoutDivisionEqualTheQuotient) {
    if (!esf::detail::avx512_available()) GTEST_SKIP() << "no AVX-512 on this CPU";
    std::vector<std::uint32_t> occupied, visited;
    for (std::uint32_t v = 1; v <= 64; ++v)
        for (std::uint32_t o = 0; o <= 64; ++o) {
            occupied.push_back(o);
            visited.push_back(v);
        }
    std::vector<float> ratio(occupied.size(), -1.0f);
    esf::detail::small_ratios_avx512(occupied.data(), visited.data(), ratio.data(),
                                     occupied.size());
    for (std::size_t i = 0; i < occupied.size(); ++i) {
        const float quotient = static_cast<float>(occupied[i]) / static_cast<float>(visited[i]);
        ASSERT_EQ(std::bit_cast<std::uint32_t>(ratio[i]), std::bit_cast<std::uint32_t>(quotient))
            << occupied[i] << " / " << visited[i];
    }
}

// The finite points of a cloud with NaN and infinite coordinates (in x, y or z alone, alone or in
// runs, in blocks with none and blocks with all), by every code path, into another vector and in
// place, against the definition.
TEST(FinitePoints, EveryPathKeepsTheFinitePointsInOrder) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> coordinate(-5.0f, 5.0f);
    std::uniform_int_distribution<int> kind(0, 9);
    const float bad[3] = {std::numeric_limits<float>::quiet_NaN(),
                          std::numeric_limits<float>::infinity(),
                          -std::numeric_limits<float>::infinity()};
    for (const std::size_t n : {0u, 1u, 15u, 16u, 17u, 100u, 1000u, 4099u}) {
        esf::Points points(n);
        esf::Points expected;
        for (std::size_t i = 0; i < n; ++i) {
            points[i] = {coordinate(rng), coordinate(rng), coordinate(rng)};
            const bool in_bad_run = (i / 40) % 3 == 1;  // whole blocks of missing points
            if (in_bad_run || kind(rng) < 3)
                points[i][static_cast<int>(i % 3)] = bad[i % 3];
            else
                expected.push_back(points[i]);
        }
        for (const auto simd : {esf::detail::SimdLevel::kAvx512, esf::detail::SimdLevel::kAvx2,
                                esf::detail::SimdLevel::kPortable}) {
            if (simd == esf::detail::SimdLevel::kAvx512 && !esf::detail::avx512_available())
                continue;
            esf::Points finite(3, Eigen::Vector3f::Ones());  // replaced, not appended to
            const std::size_t dropped = esf::detail::keep_finite_points(points, simd, finite);
            EXPECT_EQ(dropped, n - expected.size()) << n;
            EXPECT_EQ(finite, expected) << n;
            esf::Points in_place = points;  // each block written over itself
            EXPECT_EQ(esf::detail::keep_finite_in_place(in_place, simd), n - expected.size()) << n;
            EXPECT_EQ(in_place, expected) << n;
        }
        EXPECT_EQ(esf::drop_non_finite(points).points, expected) << n;
    }
}
