// The ESF descriptor on hand-made clouds: invariants, determinism, bad input, and the line
// tracer and voxel grid against hand-computed cells. The comparison with PCL's own ESF is in
// esf_pcl_oracle_test.cpp.

#include "esf/descriptors/esf/esf_descriptor.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <thread>
#include <utility>

#include "descriptors/esf/esf_points.hpp"
#include "descriptors/esf/esf_trace.hpp"
#include "descriptors/esf/esf_triangles.hpp"

namespace {

using ::testing::HasSubstr;

/// Front half of a cylinder with a lid: a partial view with IN, OUT and MIXED lines.
esf::Points partial_cylinder(std::size_t count, std::uint32_t seed = 3) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    esf::Points points(count);
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

std::string error_of(const esf::Points& points, const esf::EsfOptions& options = {}) {
    try {
        esf::compute_esf(points, options);
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "no error";
}

TEST(EsfDescriptor, IsNonNegativeAndSumsToOne) {
    for (auto sampler : {esf::EsfSampler::kFast, esf::EsfSampler::kPcl}) {
        esf::EsfOptions options;
        options.sampler = sampler;
        const auto result = esf::compute_esf(partial_cylinder(3000), options);
        double sum = 0.0;
        for (float v : result.descriptor) {
            EXPECT_GE(v, 0.0f);
            sum += v;
        }
        EXPECT_NEAR(sum, 1.0, 1e-5);
        EXPECT_EQ(result.points, 3000u);
        EXPECT_GE(result.attempts, 20000u);
    }
}

TEST(EsfDescriptor, EveryBlockIsFilledOnAPartialView) {
    const auto d = esf::compute_esf(partial_cylinder(5000)).descriptor;
    for (int b = 0; b < esf::kEsfBlocks; ++b) {
        const double block = std::accumulate(d.begin() + b * 64, d.begin() + (b + 1) * 64, 0.0);
        EXPECT_GT(block, 0.0) << esf::esf_block_names()[static_cast<std::size_t>(b)];
    }
}

TEST(EsfDescriptor, SameSeedSameOutputOtherSeedOtherOutput) {
    const auto points = partial_cylinder(4000);
    esf::EsfOptions a, b;
    a.seed = 11;
    b.seed = 12;
    const auto first = esf::compute_esf(points, a).descriptor;
    EXPECT_EQ(first, esf::compute_esf(points, a).descriptor);
    const double seed_noise = esf::l1_distance(first, esf::compute_esf(points, b).descriptor);
    EXPECT_GT(seed_noise, 0.0);
    EXPECT_LT(seed_noise, 0.2);  // Monte-Carlo noise of 20,000 samples, not another shape
}

TEST(EsfDescriptor, ReusedEstimatorMatchesFreshOne) {
    esf::EsfEstimator estimator;
    const auto small = partial_cylinder(500, 1), large = partial_cylinder(8000, 2);
    const auto first = estimator.compute(large).descriptor;
    estimator.compute(small);
    EXPECT_EQ(estimator.compute(large).descriptor, first);
    EXPECT_EQ(esf::compute_esf(large).descriptor, first);
}

TEST(EsfDescriptor, BatchDoesNotDependOnThreadCount) {
    std::vector<esf::Points> clouds;
    for (std::uint32_t i = 0; i < 6; ++i) clouds.push_back(partial_cylinder(1000 + 300 * i, i));
    clouds.push_back({});  // fails alone, the others still succeed
    const auto one = esf::compute_esf_batch(clouds, {}, 1);
    const auto two = esf::compute_esf_batch(clouds, {}, 2);
    const auto all = esf::compute_esf_batch(clouds, {}, 0);
    ASSERT_EQ(one.size(), clouds.size());
    for (std::size_t i = 0; i + 1 < clouds.size(); ++i) {
        ASSERT_TRUE(one[i].ok()) << one[i].error;
        EXPECT_EQ(one[i].result.descriptor, two[i].result.descriptor) << i;
        EXPECT_EQ(one[i].result.descriptor, all[i].result.descriptor) << i;
        EXPECT_EQ(one[i].result.descriptor, esf::compute_esf(clouds[i]).descriptor) << i;
    }
    EXPECT_FALSE(one.back().ok());
    EXPECT_THAT(one.back().error, HasSubstr("at least 3 finite points"));
}

TEST(EsfDescriptor, PoolGivesTheEstimatorsResultFromConcurrentCallers) {
    std::vector<esf::Points> clouds;
    for (std::uint32_t i = 0; i < 8; ++i) clouds.push_back(partial_cylinder(800 + 200 * i, i));
    esf::EsfOptions options;
    options.samples = 3000;
    const esf::EsfEstimatorPool pool(options);
    std::vector<esf::EsfDescriptor> got(clouds.size());
    std::vector<std::thread> threads;
    for (std::size_t t = 0; t < 4; ++t)
        threads.emplace_back([&, t] {
            for (std::size_t i = t; i < clouds.size(); i += 4)
                got[i] = pool.compute(clouds[i]).descriptor;
        });
    for (auto& thread : threads) thread.join();
    for (std::size_t i = 0; i < clouds.size(); ++i)
        EXPECT_EQ(got[i], esf::compute_esf(clouds[i], options).descriptor) << i;
    // A failing cloud gives its error and its estimator back: the pool keeps working.
    EXPECT_THROW(pool.compute(esf::Points(2, Eigen::Vector3f::Zero())), std::invalid_argument);
    EXPECT_EQ(pool.compute(clouds[0]).descriptor, got[0]);
}

/// Descriptors and attempts of kAvx2 and kPortable against kBest's.
void expect_kernels_agree(const esf::Points& points, const esf::EsfOptions& best,
                          const std::string& what) {
    const auto a = esf::compute_esf(points, best);
    for (const esf::EsfKernels kernels : {esf::EsfKernels::kAvx2, esf::EsfKernels::kPortable}) {
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
    for (const esf::EsfKernels kernels :
         {esf::EsfKernels::kBest, esf::EsfKernels::kAvx2, esf::EsfKernels::kPortable}) {
        options.kernels = kernels;
        EXPECT_THAT(error_of(line, options), HasSubstr("lie on one line")) << to_string(kernels);
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
    for (const esf::EsfKernels kernels :
         {esf::EsfKernels::kBest, esf::EsfKernels::kAvx2, esf::EsfKernels::kPortable}) {
        options.kernels = kernels;
        const std::string error = error_of(points, options);
        EXPECT_THAT(error, HasSubstr("non-degenerate triangles in 1000 random triples"));
        if (first.empty()) first = error;
        EXPECT_EQ(error, first) << to_string(kernels);
    }
}

TEST(EsfDescriptor, KernelNamesRoundTrip) {
    for (const esf::EsfKernels kernels :
         {esf::EsfKernels::kBest, esf::EsfKernels::kAvx2, esf::EsfKernels::kPortable})
        EXPECT_EQ(esf::parse_esf_kernels(esf::to_string(kernels)), kernels);
    try {
        esf::parse_esf_kernels("sse");
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "unknown ESF kernels 'sse' (expected best, avx2 or portable)");
    }
}

TEST(EsfDescriptor, InvariantToTranslationAndScale) {
    const auto points = partial_cylinder(6000);
    const auto reference = esf::compute_esf(points).descriptor;
    for (float scale : {1e6f, 1e-6f, 1000.0f}) {
        esf::Points scaled = points;
        for (auto& p : scaled) p = p * scale + Eigen::Vector3f(0.5f, -0.25f, 2.0f) * scale;
        const double d = esf::l1_distance(reference, esf::compute_esf(scaled).descriptor);
        // Identical up to the odd point whose float rounding moves it across a cell border:
        // far below the seed-to-seed noise (0.05 - 0.085).
        EXPECT_LT(d, 2e-3) << "scale " << scale;
    }
}

TEST(EsfDescriptor, NonFinitePointsAreDroppedAndCounted) {
    esf::Points points = partial_cylinder(2000);
    const auto clean = esf::compute_esf(points).descriptor;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    points.insert(points.begin() + 5, Eigen::Vector3f(nan, 0, 0));
    points.push_back({0, inf, 0});
    const auto result = esf::compute_esf(points);
    EXPECT_EQ(result.dropped_points, 2u);
    EXPECT_EQ(result.points, 2000u);
    EXPECT_EQ(result.descriptor, clean);
}

// The check for callers that drop non-finite points themselves gives compute()'s message.
TEST(EsfDescriptor, RequiringPointsGivesTheEstimatorsMessage) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    esf::Points points(7, Eigen::Vector3f(nan, 0, 0));
    points[3] = {1, 2, 3};
    const std::string from_compute = error_of(points);
    std::string from_check;
    try {
        esf::require_esf_points(1, 6);
    } catch (const std::invalid_argument& e) {
        from_check = e.what();
    }
    EXPECT_EQ(from_check, from_compute);
    EXPECT_THAT(from_check, HasSubstr("got 1 (6 non-finite dropped)"));
    EXPECT_NO_THROW(esf::require_esf_points(3, 0));
    EXPECT_THROW(esf::require_esf_points(2, 0), std::invalid_argument);
}

TEST(EsfDescriptor, BadInputGivesClearErrors) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THAT(error_of({}), HasSubstr("at least 3 finite points, got 0"));
    EXPECT_THAT(error_of({{1, 2, 3}}), HasSubstr("got 1"));
    EXPECT_THAT(error_of({{1, 2, 3}, {2, 3, 4}}), HasSubstr("got 2"));
    EXPECT_THAT(error_of(esf::Points(50, Eigen::Vector3f(nan, nan, nan))),
                HasSubstr("got 0 (50 non-finite dropped)"));
    EXPECT_THAT(error_of(esf::Points(100, Eigen::Vector3f(1, 1, 1))), HasSubstr("identical"));
    esf::Points line;
    for (int i = 0; i < 1000; ++i) {
        const float t = 0.001f * static_cast<float>(i);
        line.emplace_back(t, 2.0f * t, -t);
    }
    EXPECT_THAT(error_of(line), HasSubstr("lie on one line"));
    esf::EsfOptions pcl;
    pcl.sampler = esf::EsfSampler::kPcl;
    EXPECT_THAT(error_of(line, pcl), HasSubstr("lie on one line"));  // PCL loops forever here
    // Two distinct positions only: every triple repeats a point, none is a triangle.
    esf::Points two_spots(200, Eigen::Vector3f(0, 0, 0));
    for (std::size_t i = 0; i < 100; ++i) two_spots[i] = {1, 1, 1};
    EXPECT_THAT(error_of(two_spots), HasSubstr("degenerate cloud"));
}

TEST(EsfDescriptor, ThreeAndFewPointsWork) {
    const esf::Points triangle = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const auto result = esf::compute_esf(triangle);
    EXPECT_NEAR(std::accumulate(result.descriptor.begin(), result.descriptor.end(), 0.0), 1.0,
                1e-5);
}

TEST(EsfDescriptor, OptionsAreValidated) {
    esf::EsfOptions bad;
    bad.samples = 0;
    EXPECT_THROW(esf::EsfEstimator{bad}, std::invalid_argument);
    bad = {};
    bad.grid_size = 65;
    EXPECT_THROW(esf::EsfEstimator{bad}, std::invalid_argument);
    bad = {};
    bad.grid_size = 32;
    bad.sampler = esf::EsfSampler::kPcl;
    EXPECT_THROW(esf::EsfEstimator{bad}, std::invalid_argument);
    EXPECT_THROW(esf::parse_esf_sampler("slow"), std::invalid_argument);
    EXPECT_EQ(esf::parse_esf_sampler("pcl"), esf::EsfSampler::kPcl);
}

TEST(EsfDescriptor, SmallerGridAndFewerSamplesWork) {
    esf::EsfOptions options;
    options.grid_size = 32;
    options.samples = 5000;
    const auto d = esf::compute_esf(partial_cylinder(3000), options).descriptor;
    EXPECT_NEAR(std::accumulate(d.begin(), d.end(), 0.0), 1.0, 1e-5);
}

using esf::detail::pack_cell;

/// The SIMD line tracers (kAvx512: the build without VPOPCNTD).
constexpr esf::detail::TraceKernel kSimdKernels[] = {esf::detail::TraceKernel::kBest,
                                                     esf::detail::TraceKernel::kAvx512,
                                                     esf::detail::TraceKernel::kAvx2};

// One cell set: the 3x3x3 block around it is occupied, clipped at the border.
TEST(VoxelGrid, DilationMarksTheTwentySixNeighbours) {
    esf::detail::VoxelGrid grid;
    grid.clear();
    grid.set(pack_cell(10, 10, 10));
    grid.set(pack_cell(0, 0, 63));  // a corner: 8 cells inside the grid
    grid.dilate(64);
    int count = 0;
    for (auto w : grid.words) count += __builtin_popcountll(w);
    EXPECT_EQ(count, 27 + 8);
    EXPECT_TRUE(grid.occupied(pack_cell(9, 11, 9)));
    EXPECT_TRUE(grid.occupied(pack_cell(11, 9, 11)));
    EXPECT_FALSE(grid.occupied(pack_cell(12, 10, 10)));
    EXPECT_TRUE(grid.occupied(pack_cell(1, 1, 62)));
    EXPECT_FALSE(grid.occupied(pack_cell(2, 0, 63)));
}

// Line (0,0,0) -> (5,2,0): L = 5, a_y = 2, error starts at 2*2 - 5 = -1. By hand the visited
// cells are (0,0,0) (1,0,0) (2,1,0) (3,1,0) (4,2,0); the end cell (5,2,0) is not counted.
TEST(LineTrace, FollowsHandComputedBresenhamCells) {
    esf::detail::VoxelGrid grid;
    grid.clear();
    for (auto c : {pack_cell(0, 0, 0), pack_cell(1, 0, 0), pack_cell(2, 1, 0), pack_cell(3, 1, 0),
                   pack_cell(4, 2, 0)})
        grid.set(c);
    grid.set(pack_cell(2, 0, 0));  // next to the line, not on it
    const std::uint32_t start[] = {pack_cell(0, 0, 0), pack_cell(5, 2, 0), pack_cell(7, 7, 7)};
    const std::uint32_t end[] = {pack_cell(5, 2, 0), pack_cell(5, 2, 0), pack_cell(7, 7, 7)};
    std::uint32_t occupied[3];
    std::uint8_t visited[3];
    for (auto kernel : {esf::detail::TraceKernel::kBest, esf::detail::TraceKernel::kAvx512,
                        esf::detail::TraceKernel::kAvx2, esf::detail::TraceKernel::kScalar}) {
        esf::detail::TraceScratch scratch;
        esf::detail::trace_lines(grid, start, end, occupied, visited, scratch, kernel);
        EXPECT_EQ(occupied[0], 5);
        EXPECT_EQ(visited[0], 5);
        EXPECT_EQ(occupied[1], 0);  // zero-length line: its own (empty) cell, once
        EXPECT_EQ(visited[1], 1);
        EXPECT_EQ(occupied[2], 0);
        EXPECT_EQ(visited[2], 1);
    }
}

TEST(LineTrace, SimdKernelsMatchScalarOnRandomLines) {
    std::mt19937 rng(5);
    std::uniform_int_distribution<std::uint32_t> coord(0, 63);
    esf::detail::VoxelGrid grid;
    grid.clear();
    for (int i = 0; i < 3000; ++i) grid.set(pack_cell(coord(rng), coord(rng), coord(rng)));
    grid.dilate(64);
    const std::size_t n = 10007;  // not a multiple of the lane count
    std::vector<std::uint32_t> starts(n), ends(n);
    for (std::size_t i = 0; i < n; ++i) {
        starts[i] = pack_cell(coord(rng), coord(rng), coord(rng));
        ends[i] = i % 7 == 0 ? starts[i] : pack_cell(coord(rng), coord(rng), coord(rng));
    }
    std::vector<std::uint32_t> expected(n), actual(n);
    std::vector<std::uint8_t> expected_visited(n), actual_visited(n);
    esf::detail::trace_lines_scalar(grid, starts, ends, expected, expected_visited);
    for (auto kernel : kSimdKernels) {
        esf::detail::TraceScratch scratch;
        esf::detail::trace_lines(grid, starts, ends, actual, actual_visited, scratch, kernel);
        EXPECT_EQ(actual, expected);
        EXPECT_EQ(actual_visited, expected_visited);
    }
    for (std::size_t i = 0; i < n; ++i)
        ASSERT_EQ(expected_visited[i], esf::detail::visited_cells(starts[i], ends[i]));
}

// Both dilation kernels against the definition, on random grids of every side ESF allows.
TEST(VoxelGrid, DilationKernelsMatchTheDefinition) {
    std::mt19937 rng(3);
    for (int side : {8, 30, 40, 62, 64}) {
        std::uniform_int_distribution<std::uint32_t> coord(0, static_cast<std::uint32_t>(side) - 1);
        esf::detail::VoxelGrid grid;
        grid.clear();
        for (int i = 0; i < 150; ++i) grid.set(pack_cell(coord(rng), coord(rng), coord(rng)));
        grid.set(pack_cell(0, 0, 0));
        grid.set(pack_cell(static_cast<std::uint32_t>(side) - 1, 0,
                           static_cast<std::uint32_t>(side) - 1));
        esf::detail::VoxelGrid expected;
        expected.clear();
        for (int z = 0; z < side; ++z)
            for (int y = 0; y < side; ++y)
                for (int x = 0; x < side; ++x) {
                    bool near = false;
                    for (int dz = -1; dz <= 1; ++dz)
                        for (int dy = -1; dy <= 1; ++dy)
                            for (int dx = -1; dx <= 1; ++dx) {
                                const int a = x + dx, b = y + dy, c = z + dz;
                                if (a >= 0 && b >= 0 && c >= 0 && a < side && b < side && c < side)
                                    near = near || grid.occupied(pack_cell(a, b, c));
                            }
                    if (near) expected.set(pack_cell(x, y, z));
                }
        for (bool simd : {true, false}) {
            esf::detail::VoxelGrid dilated = grid;
            dilated.dilate(side, simd);
            EXPECT_EQ(dilated.words, expected.words) << "side " << side << " simd " << simd;
        }
    }
}

/// `count` lines between random pairs of `points`.
struct RandomLines {
    std::vector<std::uint32_t> starts, ends;
};

RandomLines lines_between(const std::vector<std::uint32_t>& points, std::size_t count,
                          std::mt19937& rng) {
    RandomLines lines{std::vector<std::uint32_t>(count), std::vector<std::uint32_t>(count)};
    std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
    for (std::size_t i = 0; i < count; ++i)
        lines.starts[i] = points[pick(rng)], lines.ends[i] = points[pick(rng)];
    return lines;
}

/// The kernel's counts for `lines` equal the scalar reference's.
void expect_kernel_matches_scalar(const esf::detail::VoxelGrid& grid, const RandomLines& lines,
                                  esf::detail::TraceKernel kernel, esf::detail::LineEnds ends_hint,
                                  esf::detail::TraceScratch& scratch, const std::string& context) {
    const std::size_t n = lines.starts.size();
    std::vector<std::uint32_t> expected(n), actual(n);
    std::vector<std::uint8_t> expected_visited(n), actual_visited(n);
    esf::detail::trace_lines_scalar(grid, lines.starts, lines.ends, expected, expected_visited);
    esf::detail::trace_lines(grid, lines.starts, lines.ends, actual, actual_visited, scratch,
                             kernel, ends_hint);
    EXPECT_EQ(actual, expected) << context;
    EXPECT_EQ(actual_visited, expected_visited) << context;
}

// As a descriptor's lines: between cells set before the dilation, in a sparse grid whose empty
// rows and grid borders are where the cube look-ups of the AVX-512 kernel can go wrong.
TEST(LineTrace, SimdKernelsMatchScalarBetweenPointCellsOfASparseGrid) {
    std::mt19937 rng(11);
    std::uniform_int_distribution<std::uint32_t> coord(0, 63), edge(0, 1);
    esf::detail::VoxelGrid grid;
    grid.clear();
    std::vector<std::uint32_t> points;
    for (int i = 0; i < 300; ++i) {
        // Half of the points on a face of the grid, so that lines run along its borders.
        std::uint32_t c[3] = {coord(rng), coord(rng), coord(rng)};
        if (i % 2 == 0) c[i % 3] = 63 * edge(rng);
        points.push_back(pack_cell(c[0], c[1], c[2]));
        grid.set(points.back());
    }
    grid.dilate(64);
    const RandomLines lines = lines_between(points, 20011, rng);
    for (auto ends_hint : {esf::detail::LineEnds::kAny, esf::detail::LineEnds::kSetBeforeDilation})
        for (auto kernel : kSimdKernels) {
            esf::detail::TraceScratch scratch;
            expect_kernel_matches_scalar(grid, lines, kernel, ends_hint, scratch, "");
        }
}

// One scratch serves many grids, as in an estimator: tables built for one grid must not leak
// into the next (each grid fills a different corner of the cube).
TEST(LineTrace, SimdKernelsReuseTheirScratchAcrossGrids) {
    std::mt19937 rng(5);
    for (auto kernel : kSimdKernels) {
        esf::detail::TraceScratch scratch;
        for (std::uint32_t corner = 0; corner < 8; ++corner) {
            std::uniform_int_distribution<std::uint32_t> coord(0, 40);
            esf::detail::VoxelGrid grid;
            grid.clear();
            std::vector<std::uint32_t> points;
            for (int i = 0; i < 200; ++i) {
                std::uint32_t c[3];
                for (int k = 0; k < 3; ++k) c[k] = (corner >> k & 1) ? 63 - coord(rng) : coord(rng);
                points.push_back(pack_cell(c[0], c[1], c[2]));
                grid.set(points.back());
            }
            grid.dilate(64);
            expect_kernel_matches_scalar(grid, lines_between(points, 5003, rng), kernel,
                                         esf::detail::LineEnds::kSetBeforeDilation, scratch,
                                         "corner " + std::to_string(corner));
        }
    }
}

/// A line of `length` steps along `axis` (0, 1, 2) from a random cell, up the axis; its minor
/// axes move at most `length` cells either way, at random.
std::pair<std::uint32_t, std::uint32_t> line_along(int axis, std::uint32_t length,
                                                   std::mt19937& rng) {
    std::uniform_int_distribution<std::uint32_t> major(0, 63 - length), minor(0, 63);
    std::uint32_t from[3], to[3];
    from[axis] = major(rng);
    to[axis] = from[axis] + length;
    const int m1 = axis == 0 ? 1 : 0, m2 = axis == 2 ? 1 : 2;  // the minor axes, in order
    for (const int m : {m1, m2}) from[m] = minor(rng);
    for (const int m : {m1, m2}) {
        std::uniform_int_distribution<std::uint32_t> end(from[m] >= length ? from[m] - length : 0,
                                                         std::min(63u, from[m] + length));
        to[m] = end(rng);
    }
    return {pack_cell(from[0], from[1], from[2]), pack_cell(to[0], to[1], to[2])};
}

// Lines of one length in whole groups of 16 (and a few more), for every length: groups whose
// lanes all end at the same cell finish without per-lane masks in the AVX-512 kernel.
TEST(LineTrace, SimdKernelsMatchScalarOnGroupsOfOneLength) {
    std::mt19937 rng(17);
    esf::detail::VoxelGrid grid;
    grid.clear();
    std::uniform_int_distribution<std::uint32_t> coord(0, 63);
    std::vector<std::uint32_t> points;
    for (int i = 0; i < 2000; ++i) {
        points.push_back(pack_cell(coord(rng), coord(rng), coord(rng)));
        grid.set(points.back());
    }
    grid.dilate(64);
    RandomLines lines;
    for (std::uint32_t length = 0; length < 64; ++length)
        for (int k = 0; k < 32 + static_cast<int>(length % 5); ++k) {
            const auto [a, b] = line_along(0, length, rng);
            lines.starts.push_back(k % 2 ? a : b);
            lines.ends.push_back(k % 2 ? b : a);
        }
    for (auto kernel : kSimdKernels) {
        esf::detail::TraceScratch scratch;
        expect_kernel_matches_scalar(grid, lines, kernel, esf::detail::LineEnds::kAny, scratch, "");
    }
}

// Lengths whose lines fill several of the AVX-512 kernel's chunks of 256 lines exactly, by one
// line more or one less, in shuffled order: every chunk boundary and last, partly filled group.
TEST(LineTrace, SimdKernelsMatchScalarWhenOneLengthFillsSeveralChunks) {
    std::mt19937 rng(29);
    esf::detail::VoxelGrid grid;
    grid.clear();
    std::uniform_int_distribution<std::uint32_t> coord(0, 63);
    for (int i = 0; i < 3000; ++i) grid.set(pack_cell(coord(rng), coord(rng), coord(rng)));
    grid.dilate(64);
    RandomLines lines;
    const std::pair<std::uint32_t, int> lengths[] = {{7, 255},  {9, 256},   {12, 257},
                                                     {20, 512}, {30, 1001}, {63, 3}};
    for (const auto& [length, count] : lengths)
        for (int k = 0; k < count; ++k) {
            const auto [a, b] = line_along(2, length, rng);
            lines.starts.push_back(a);
            lines.ends.push_back(b);
        }
    std::vector<std::size_t> order(lines.starts.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::shuffle(order.begin(), order.end(), rng);
    RandomLines shuffled;
    for (const std::size_t i : order) {
        shuffled.starts.push_back(lines.starts[i]);
        shuffled.ends.push_back(lines.ends[i]);
    }
    for (auto kernel : kSimdKernels) {
        esf::detail::TraceScratch scratch;
        expect_kernel_matches_scalar(grid, shuffled, kernel, esf::detail::LineEnds::kAny, scratch,
                                     "");
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

// The first call runs the widest kernel and its time does not count (cold caches): recorded
// here as far faster than any later call, so that counting it would change every choice below.
namespace {
void warm_up(esf::detail::TraceKernelTrials& trials) {
    for (int i = 0; i < esf::detail::TraceKernelTrials::kWarmUpCalls; ++i) {
        ASSERT_EQ(trials.next(), esf::detail::TraceKernel::kBest);
        trials.record(esf::detail::TraceKernel::kBest, 1e-6, 1000);
    }
}
}  // namespace

// Times are compared per visited cell (calls trace different clouds), and a narrower kernel must
// beat the widest by the margin.
TEST(TraceKernelTrials, ComparesTimePerCellAndKeepsTheWidestWithinTheMargin) {
    using esf::detail::TraceKernel;
    using esf::detail::TraceKernelTrials;
    for (const double narrower_speed : {0.98, 0.90}) {  // time per cell against the widest
        TraceKernelTrials trials;
        if (trials.decided()) return;  // one kernel on this CPU
        warm_up(trials);
        while (!trials.decided()) {
            const TraceKernel kernel = trials.next();
            // The widest traces twice the cells in twice the time: the same time per cell.
            if (kernel == TraceKernel::kBest)
                trials.record(kernel, 2.0, 2000);
            else
                trials.record(kernel, narrower_speed, 1000);
        }
        EXPECT_EQ(trials.next() == TraceKernel::kBest,
                  narrower_speed > 1.0 - TraceKernelTrials::kMargin)
            << narrower_speed;
    }
}

// A narrower kernel far slower than the widest takes no more turns after the round in which it
// fell behind; one within kDrop takes all its turns.
TEST(TraceKernelTrials, DropsKernelsFarSlowerThanTheWidestAfterARound) {
    using esf::detail::TraceKernel;
    using esf::detail::TraceKernelTrials;
    {
        TraceKernelTrials trials;
        if (trials.decided()) return;  // one kernel on this CPU
    }
    for (const double slower :
         {1.0 + TraceKernelTrials::kDrop + 0.05, 1.0 + TraceKernelTrials::kDrop - 0.05}) {
        TraceKernelTrials trials;
        warm_up(trials);
        std::vector<TraceKernel> tried;
        while (!trials.decided() && tried.size() < 100) {
            const TraceKernel kernel = trials.next();
            tried.push_back(kernel);
            trials.record(kernel, kernel == TraceKernel::kBest ? 1.0 : slower, 1000);
        }
        ASSERT_TRUE(trials.decided());
        EXPECT_EQ(trials.next(), TraceKernel::kBest) << slower;
        const std::size_t kinds = static_cast<std::size_t>(
            std::find(tried.begin() + 1, tried.end(), TraceKernel::kBest) - tried.begin());
        if (slower > 1.0 + TraceKernelTrials::kDrop) {
            // One round, then the widest alone is left: chosen at once.
            EXPECT_EQ(tried.size(), kinds) << slower;
        } else {
            EXPECT_EQ(tried.size(), kinds * TraceKernelTrials::kRounds) << slower;
        }
    }
    // Dropped after the second round: the narrower kernels were as fast as the widest in the
    // first, then the widest got twice as fast.
    TraceKernelTrials trials;
    warm_up(trials);
    std::vector<TraceKernel> tried;
    while (!trials.decided() && tried.size() < 100) {
        const TraceKernel kernel = trials.next();
        const bool widest_again = kernel == TraceKernel::kBest && !tried.empty();
        tried.push_back(kernel);
        trials.record(kernel, widest_again ? 0.5 : 1.0, 1000);
    }
    ASSERT_TRUE(trials.decided());
    EXPECT_EQ(trials.next(), TraceKernel::kBest);
    const auto kinds = static_cast<std::size_t>(
        std::find(tried.begin() + 1, tried.end(), TraceKernel::kBest) - tried.begin());
    EXPECT_EQ(tried.size(), 2 * kinds);
}

TEST(TraceKernelTrials, TriesEachKernelInTurnThenKeepsTheFastest) {
    using esf::detail::TraceKernel;
    esf::detail::TraceKernelTrials trials;
    if (trials.decided()) {  // a CPU with one kernel: nothing to try
        EXPECT_EQ(trials.next(), TraceKernel::kBest);
        return;
    }
    warm_up(trials);
    std::vector<TraceKernel> tried;
    while (!trials.decided() && tried.size() < 100) {
        const TraceKernel kernel = trials.next();
        tried.push_back(kernel);
        // The AVX2 kernel is made the fastest after the first round (at most three kernels).
        const bool later_round = tried.size() > 3;
        trials.record(kernel, kernel == TraceKernel::kAvx2 && later_round ? 1.0 : 2.0, 1000);
    }
    ASSERT_TRUE(trials.decided());
    const std::size_t kinds = tried.size() / esf::detail::TraceKernelTrials::kRounds;
    ASSERT_EQ(tried.size(), kinds * esf::detail::TraceKernelTrials::kRounds);
    EXPECT_EQ(tried.front(), TraceKernel::kBest);  // the widest first
    for (std::size_t i = kinds; i < tried.size(); ++i) EXPECT_EQ(tried[i], tried[i - kinds]);
    EXPECT_EQ(trials.next(), TraceKernel::kAvx2);
    trials.record(TraceKernel::kAvx2, 100.0, 1000);  // the choice stays
    EXPECT_EQ(trials.next(), TraceKernel::kAvx2);
}
