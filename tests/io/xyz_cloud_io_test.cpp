// Plain-text clouds (src/io/xyz_cloud_io.cpp).

#include "support/cloud_io_test_util.hpp"

namespace {

using namespace esf::test;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// ---------------------------------------------------------------------------------------------
// Plain text

TEST(XyzRead, CommentsCommasBlankLinesAndExtraColumns) {
    const esf::PointCloud cloud = xyz_from(
        "# x y z\n"
        "1 2 3\n"
        "\n"
        "4,5,6  # trailing comment\n"
        "  7\t8\t9 10 11\r\n"
        "1e-3, -2.5e2 ,+3\n"
        "   # indented comment\n");
    ASSERT_EQ(cloud.points.size(), 4u);
    EXPECT_EQ(cloud.points[0], Eigen::Vector3f(1, 2, 3));
    EXPECT_EQ(cloud.points[1], Eigen::Vector3f(4, 5, 6));
    EXPECT_EQ(cloud.points[2], Eigen::Vector3f(7, 8, 9));
    EXPECT_EQ(cloud.points[3], Eigen::Vector3f(1e-3f, -250.0f, 3.0f));
    EXPECT_EQ(cloud.width, 4u);
    EXPECT_EQ(cloud.height, 1u);
    EXPECT_TRUE(cloud.labels.empty());
}

TEST(XyzRead, OnlyCommentsGiveAnEmptyCloud) {
    EXPECT_TRUE(xyz_from("# nothing here\n\n").points.empty());
}

TEST(XyzErrors, LineNumbers) {
    EXPECT_EQ(io_error([] { xyz_from("# c\n1 2 3\n\n4 5\n"); }),
              "mem.xyz:4: expected at least 3 numbers (x y z), got 2");
    EXPECT_EQ(io_error([] { xyz_from("1 2 3\n1 2 abc\n"); }), "mem.xyz:2: not a number: 'abc'");
    EXPECT_EQ(io_error([] { xyz_from(""); }), "mem.xyz: empty file");
}

TEST(XyzErrors, ValuesBeyondTheFloatRange) {
    EXPECT_EQ(io_error([] { xyz_from("1 2 3\n1e39 2 3\n"); }),
              "mem.xyz:2: out of float range: '1e39'");
    const esf::PointCloud tiny = xyz_from("1e-50, -1e-50, 1e-40\n");
    EXPECT_EQ(bits(tiny.points[0].x()), bits(0.0f));
    EXPECT_EQ(bits(tiny.points[0].y()), bits(-0.0f));
    EXPECT_EQ(tiny.points[0].z(), 1e-40f);
}

TEST(XyzWrite, RoundTripBitForBitWithNaN) {
    const esf::PointCloud cloud = sample_cloud(200, true);
    std::ostringstream out;
    esf::write_xyz(out, cloud);
    const esf::PointCloud back = xyz_from(out.str());
    expect_same_points(back.points, cloud.points);  // NaN written "nan", read back as NaN
    EXPECT_EQ(back.width, 200u);
    EXPECT_TRUE(back.labels.empty());
    // Shortest round-trip text: 0.1f is "0.1", not 0.100000001.
    esf::PointCloud simple;
    simple.points = {{0.1f, -2.0f, 1e-40f}};
    std::ostringstream line;
    esf::write_xyz(line, simple);
    EXPECT_EQ(line.str(), "0.1 -2 1e-40\n");
}

}  // namespace
