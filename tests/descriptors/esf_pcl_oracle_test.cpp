// ESF against its reference, pcl::ESFEstimation of Debian's PCL 1.13, on real clouds.
//
// PCL seeds rand() from time(NULL) on every call. This executable defines time() itself, so
// the reference uses the seed the test chooses (the symbol is looked up through the dynamic
// linker, so this definition wins; docs/esf.md, "Sampling").

#include <gtest/gtest.h>
#include <pcl/features/esf.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <ctime>
#include <numeric>
#include <string>
#include <vector>

#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "support/test_data.hpp"

namespace {
time_t pinned_time = 12345;
}

extern "C" time_t time(time_t* out) {
    if (out) *out = pinned_time;
    return pinned_time;
}

namespace {

const std::vector<std::string> kClouds = {
    "real/pcl/milk_test.pcd",
    "real/objects/pcl_milkscene_o2.pcd",
    "real/objects/pcl_milkscene_o3.pcd",
    "real/objects/pcl_mugscene_o1.pcd",
    "real/objects/mosd_learn0_o2.pcd",
    "real/objects/mosd_learn12_o3.pcd",
};

esf::Points load_finite(const std::string& relative) {
    pcl::PointCloud<pcl::PointXYZ> cloud;
    const std::string path = esf::test::data_file(relative).string();
    if (pcl::io::loadPCDFile(path, cloud) != 0) throw std::runtime_error("cannot read " + path);
    esf::Points points;
    for (const auto& p : cloud)
        if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
            points.emplace_back(p.x, p.y, p.z);
    return points;
}

esf::EsfDescriptor pcl_esf(const esf::Points& points, time_t seed) {
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    for (const auto& p : points) cloud->emplace_back(p.x(), p.y(), p.z());
    cloud->is_dense = true;
    pcl::ESFEstimation<pcl::PointXYZ, pcl::ESFSignature640> estimation;
    estimation.setInputCloud(cloud);
    pcl::PointCloud<pcl::ESFSignature640> out;
    pinned_time = seed;
    estimation.compute(out);
    esf::EsfDescriptor d{};
    std::copy(std::begin(out[0].histogram), std::end(out[0].histogram), d.begin());
    return d;
}

esf::EsfDescriptor ours(const esf::Points& points, std::uint64_t seed, esf::EsfSampler sampler) {
    esf::EsfOptions options;
    options.seed = seed;
    options.sampler = sampler;
    return esf::compute_esf(points, options).descriptor;
}

TEST(EsfPclOracle, PclSamplerIsBitExact) {
    ESF_REQUIRE_DATA("real/pcl/milk_test.pcd");
    for (const auto& file : kClouds) {
        const esf::Points points = load_finite(file);
        for (time_t seed : {12345, 1, 987654321}) {
            const auto expected = pcl_esf(points, seed);
            const auto actual =
                ours(points, static_cast<std::uint64_t>(seed), esf::EsfSampler::kPcl);
            int differing = 0;
            for (int i = 0; i < esf::kEsfSize; ++i) differing += expected[i] != actual[i];
            EXPECT_EQ(differing, 0) << file << " seed " << seed;
            for (int i = 0; i < esf::kEsfSize && differing; ++i)
                ASSERT_EQ(expected[i], actual[i]) << file << " seed " << seed << " bin " << i;
        }
    }
}

// PCL's own test cloud (test/milk.pcd of the PCL repository) with seed 12345: the block sums
// Debian's PCL 1.13 gives, measured once and kept here as the reference.
TEST(EsfPclOracle, MilkReferenceBlockSums) {
    ESF_REQUIRE_DATA("real/pcl/milk_test.pcd");
    const esf::Points points = load_finite("real/pcl/milk_test.pcd");
    ASSERT_EQ(points.size(), 13704u);
    const auto d = ours(points, 12345, esf::EsfSampler::kPcl);
    const double expected[esf::kEsfBlocks] = {0.032384, 0.009295, 0.093774, 0.024926, 0.009020,
                                              0.104008, 0.150666, 0.134357, 0.294379, 0.147190};
    for (int b = 0; b < esf::kEsfBlocks; ++b) {
        const double sum = std::accumulate(d.begin() + b * 64, d.begin() + (b + 1) * 64, 0.0);
        EXPECT_NEAR(sum, expected[b], 1e-6) << esf::esf_block_names()[static_cast<std::size_t>(b)];
    }
}

// The fast sampler is statistically the reference: its mean L1 distance to PCL's descriptors is
// within 1.1x PCL's own seed-to-seed distance (the Monte-Carlo noise floor).
TEST(EsfPclOracle, FastSamplerIsStatisticallyFaithful) {
    ESF_REQUIRE_DATA("real/pcl/milk_test.pcd");
    constexpr int kSeeds = 6;
    double within_sum = 0.0, across_sum = 0.0;
    int within_count = 0, across_count = 0;
    for (const auto& file : kClouds) {
        const esf::Points points = load_finite(file);
        std::vector<esf::EsfDescriptor> reference, fast;
        for (int s = 0; s < kSeeds; ++s) {
            reference.push_back(pcl_esf(points, 1000 + s));
            fast.push_back(ours(points, static_cast<std::uint64_t>(s), esf::EsfSampler::kFast));
        }
        double within = 0.0, across = 0.0;
        int nw = 0, na = 0;
        for (int s = 0; s < kSeeds; ++s)
            for (int t = 0; t < kSeeds; ++t) {
                if (s < t) within += esf::l1_distance(reference[s], reference[t]), ++nw;
                across += esf::l1_distance(fast[s], reference[t]), ++na;
            }
        std::cout << file << ": PCL seed-to-seed L1 " << within / nw << ", fast-to-PCL L1 "
                  << across / na << "\n";
        EXPECT_LT(across / na, 1.25 * within / nw) << file;
        within_sum += within, within_count += nw;
        across_sum += across, across_count += na;
    }
    const double within = within_sum / within_count, across = across_sum / across_count;
    std::cout << "all clouds: PCL seed-to-seed L1 " << within << ", fast-to-PCL L1 " << across
              << " (ratio " << across / within << ")\n";
    EXPECT_LE(across, 1.1 * within);
}

}  // namespace
