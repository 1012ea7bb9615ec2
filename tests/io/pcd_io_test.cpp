// PCD reading and writing (src/io/pcd_reader.cpp, src/io/pcd_writer.cpp, src/io/pcd_header.cpp):
// round trips in memory for every encoding, PCL as the oracle both ways, hand-written layouts,
// error paths by message, and every shared real cloud against PCL's loader.

#ifdef ESF_TEST_WITH_PCL  // PCL as the oracle
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#endif

#include <iostream>

#include "support/cloud_io_test_util.hpp"
#include "support/test_data.hpp"

namespace {

using namespace esf::test;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// ---------------------------------------------------------------------------------------------
// PCD round trips in memory, every encoding

class PcdRoundTrip : public ::testing::TestWithParam<esf::PcdEncoding> {};

INSTANTIATE_TEST_SUITE_P(Encodings, PcdRoundTrip,
                         ::testing::Values(esf::PcdEncoding::kAscii, esf::PcdEncoding::kBinary,
                                           esf::PcdEncoding::kBinaryCompressed),
                         [](const auto& encoding) {
                             switch (encoding.param) {
                                 case esf::PcdEncoding::kAscii:
                                     return std::string("Ascii");
                                 case esf::PcdEncoding::kBinary:
                                     return std::string("Binary");
                                 default:
                                     return std::string("BinaryCompressed");
                             }
                         });

TEST_P(PcdRoundTrip, KeepsPointsBitForBit) {
    const esf::PointCloud cloud = sample_cloud(1000, false);
    const esf::PointCloud back = pcd_from(pcd_bytes(cloud, GetParam()));
    expect_same_points(back.points, cloud.points);
    EXPECT_EQ(back.width, 1000u);
    EXPECT_EQ(back.height, 1u);
    EXPECT_TRUE(back.labels.empty());
}

TEST_P(PcdRoundTrip, KeepsLabels) {
    const esf::PointCloud cloud = sample_cloud(300, true);
    const esf::PointCloud back = pcd_from(pcd_bytes(cloud, GetParam()));
    expect_same_points(back.points, cloud.points);
    EXPECT_EQ(back.labels, cloud.labels);
}

TEST_P(PcdRoundTrip, KeepsOrganisedLayout) {
    esf::PointCloud cloud = sample_cloud(40, true);
    cloud.width = 8;
    cloud.height = 5;
    const esf::PointCloud back = pcd_from(pcd_bytes(cloud, GetParam()));
    EXPECT_EQ(back.width, 8u);
    EXPECT_EQ(back.height, 5u);
    EXPECT_TRUE(back.organised());
    expect_same_points(back.points, cloud.points);
}

TEST_P(PcdRoundTrip, WritesUnorganisedWhenLayoutDoesNotFit) {
    esf::PointCloud cloud = sample_cloud(10, false);
    cloud.width = 7;
    cloud.height = 3;
    const esf::PointCloud back = pcd_from(pcd_bytes(cloud, GetParam()));
    EXPECT_EQ(back.width, 10u);
    EXPECT_EQ(back.height, 1u);
}

TEST_P(PcdRoundTrip, EmptyCloud) {
    const esf::PointCloud back = pcd_from(pcd_bytes(esf::PointCloud{}, GetParam()));
    EXPECT_TRUE(back.points.empty());
    EXPECT_EQ(back.width, 0u);
    EXPECT_EQ(back.height, 1u);
}

#ifdef ESF_TEST_WITH_PCL
TEST_P(PcdRoundTrip, PclReadsWhatWeWrite) {
    TempDir dir;
    esf::PointCloud cloud = sample_cloud(60, true);
    cloud.width = 10;
    cloud.height = 6;
    const std::string path = dir.file("ours.pcd");
    esf::write_pcd(path, cloud, GetParam());
    pcl::PointCloud<pcl::PointXYZL> pcl_cloud;
    ASSERT_EQ(pcl::io::loadPCDFile(path, pcl_cloud), 0);
    ASSERT_EQ(pcl_cloud.size(), cloud.points.size());
    EXPECT_EQ(pcl_cloud.width, 10u);
    EXPECT_EQ(pcl_cloud.height, 6u);
    esf::Points pcl_points;
    for (const auto& p : pcl_cloud) pcl_points.emplace_back(p.x, p.y, p.z);
    expect_same_points(pcl_points, cloud.points);
    for (std::size_t i = 0; i < cloud.labels.size(); ++i) {
        ASSERT_EQ(pcl_cloud[i].label, cloud.labels[i]) << "point " << i;
    }
}
#endif

#ifdef ESF_TEST_WITH_PCL
TEST_P(PcdRoundTrip, ReadsWhatPclWrites) {
    TempDir dir;
    pcl::PointCloud<pcl::PointXYZRGBNormal> pcl_cloud(5, 4);
    std::mt19937 gen(3);
    std::uniform_real_distribution<float> coordinate(-2.0f, 2.0f);
    for (auto& p : pcl_cloud) {
        p.x = coordinate(gen);
        p.y = coordinate(gen);
        p.z = coordinate(gen);
        p.normal_x = 1.0f;
        p.rgba = 0xff102030u;
    }
    pcl_cloud[7].x = pcl_cloud[7].y = pcl_cloud[7].z = kNaN;
    const std::string path = dir.file("pcl.pcd");
    pcl::PCDWriter writer;
    switch (GetParam()) {
        case esf::PcdEncoding::kAscii:
            ASSERT_EQ(writer.writeASCII(path, pcl_cloud), 0);
            break;
        case esf::PcdEncoding::kBinary:
            ASSERT_EQ(writer.writeBinary(path, pcl_cloud), 0);
            break;
        case esf::PcdEncoding::kBinaryCompressed:
            ASSERT_EQ(writer.writeBinaryCompressed(path, pcl_cloud), 0);
            break;
    }
    pcl::PointCloud<pcl::PointXYZ> reloaded;
    ASSERT_EQ(pcl::io::loadPCDFile(path, reloaded), 0);
    const esf::PointCloud ours = esf::read_pcd(path);
    EXPECT_EQ(ours.width, 5u);
    EXPECT_EQ(ours.height, 4u);
    esf::Points expected;
    for (const auto& p : reloaded) expected.emplace_back(p.x, p.y, p.z);
    expect_same_points(ours.points, expected);
    EXPECT_TRUE(std::isnan(ours.points[7].x()));
}
#endif

TEST(PcdWrite, RejectsLabelCountMismatch) {
    esf::PointCloud cloud = sample_cloud(5, false);
    cloud.labels = {1, 2};
    std::ostringstream out;
    EXPECT_THROW(esf::write_pcd(out, cloud), std::invalid_argument);
}

TEST(PcdWrite, BinaryHeaderIsPclStyle) {
    const std::string bytes = pcd_bytes(sample_cloud(2, true), esf::PcdEncoding::kBinary);
    EXPECT_THAT(bytes, StartsWith("# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
                                  "FIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
                                  "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\n"
                                  "DATA binary\n"));
    EXPECT_EQ(bytes.size(), bytes.find("DATA binary\n") + 12 + 2 * 16);
}

// ---------------------------------------------------------------------------------------------
// PCD: hand-written files with other layouts

TEST(PcdRead, AsciiWithOtherFieldsPaddingAndDoubles) {
    // Tokens per point: _ (2) rgb x(F8) y z normal_x (3) label = 10.
    const std::string file =
        "# .PCD v0.7 - Point Cloud Data file format\r\n"
        "VERSION 0.7\r\n"
        "FIELDS _ rgb x y z normal_x label\r\n"
        "SIZE 1 4 8 4 4 4 4\r\n"
        "TYPE U F F F F F U\r\n"
        "COUNT 2 1 1 1 1 3 1\r\n"
        "WIDTH 3\r\n"
        "HEIGHT 1\r\n"
        "# a comment inside the header\r\n"
        "VIEWPOINT 0 0 0 1 0 0 0\r\n"
        "POINTS 3\r\n"
        "DATA ascii\r\n"
        "0 0 4.2108e+06 0.1 0.2 0.3 1 0 0 5\r\n"
        "\r\n"
        "0 0 0 -1.5e2 +2 nan 0 1 0 4294967295\n"
        "0 0 0 1e-7\t3.25   -0 0 0 1 0\n";
    const esf::PointCloud cloud = pcd_from(file);
    ASSERT_EQ(cloud.points.size(), 3u);
    EXPECT_EQ(bits(cloud.points[0].x()), bits(static_cast<float>(0.1)));  // F8: via double
    EXPECT_EQ(bits(cloud.points[0].y()), bits(0.2f));
    EXPECT_EQ(bits(cloud.points[0].z()), bits(0.3f));
    EXPECT_EQ(cloud.points[1].x(), -150.0f);
    EXPECT_EQ(cloud.points[1].y(), 2.0f);
    EXPECT_TRUE(std::isnan(cloud.points[1].z()));
    EXPECT_EQ(bits(cloud.points[2].x()), bits(static_cast<float>(1e-7)));
    EXPECT_EQ(cloud.points[2].y(), 3.25f);
    EXPECT_EQ(bits(cloud.points[2].z()), bits(-0.0f));
    EXPECT_EQ(cloud.labels, (std::vector<std::uint32_t>{5, 4294967295u, 0}));
}

TEST(PcdRead, Version06HeaderWithoutVersionViewpointOrCount) {
    const esf::PointCloud cloud = pcd_from(
        "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n"
        "DATA ascii\n1 2 3\n4 5 6\n");
    ASSERT_EQ(cloud.points.size(), 2u);
    EXPECT_EQ(cloud.points[1], Eigen::Vector3f(4, 5, 6));
    EXPECT_EQ(cloud.width, 2u);

    // Older still: COLUMNS, float by default, only POINTS.
    const esf::PointCloud old = pcd_from("COLUMNS x y z\nPOINTS 1\nDATA ascii\n7 8 9\n");
    ASSERT_EQ(old.points.size(), 1u);
    EXPECT_EQ(old.points[0], Eigen::Vector3f(7, 8, 9));
    EXPECT_EQ(old.width, 1u);
    EXPECT_EQ(old.height, 1u);
}

/// Layout of the binary tests: _ (U1 x3), x F8, y F4, z I2, label U2, rgb F4 = 23 bytes.
constexpr std::string_view kMixedHeader =
    "VERSION 0.7\nFIELDS _ x y z label rgb\nSIZE 1 8 4 2 2 4\nTYPE U F F I U F\n"
    "COUNT 3 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n";

TEST(PcdRead, BinaryAnyLayout) {
    Bytes b;
    b.text(kMixedHeader).text("DATA binary\n");
    b.put<std::uint8_t>(9).put<std::uint8_t>(9).put<std::uint8_t>(9);
    b.put(0.1).put(2.5f).put<std::int16_t>(-7).put<std::uint16_t>(3).put(1.0f);
    b.put<std::uint8_t>(0).put<std::uint8_t>(0).put<std::uint8_t>(0);
    b.put(-1e10).put(kNaN).put<std::int16_t>(32767).put<std::uint16_t>(65535).put(0.0f);
    const esf::PointCloud cloud = pcd_from(b.str());
    ASSERT_EQ(cloud.points.size(), 2u);
    EXPECT_EQ(bits(cloud.points[0].x()), bits(static_cast<float>(0.1)));
    EXPECT_EQ(cloud.points[0].y(), 2.5f);
    EXPECT_EQ(cloud.points[0].z(), -7.0f);
    EXPECT_EQ(cloud.points[1].x(), -1e10f);
    EXPECT_TRUE(std::isnan(cloud.points[1].y()));
    EXPECT_EQ(cloud.points[1].z(), 32767.0f);
    EXPECT_EQ(cloud.labels, (std::vector<std::uint32_t>{3, 65535}));
}

TEST(PcdRead, BinaryCompressedSkipsPaddingBlocksLikePcl) {
    // One block per field, padding '_' not stored (PCL's writer and reader).
    std::string raw = Bytes().put(0.1).put(-2.0).str();                // x F8
    raw += Bytes().put(2.5f).put(kNaN).str();                          // y F4
    raw += Bytes().put<std::int16_t>(-7).put<std::int16_t>(1).str();   // z I2
    raw += Bytes().put<std::uint16_t>(3).put<std::uint16_t>(4).str();  // label U2
    raw += Bytes().put(1.0f).put(2.0f).str();                          // rgb F4
    const std::string file =
        std::string(kMixedHeader) + "DATA binary_compressed\n" +
        compressed_body(lzf_literals(raw), static_cast<std::uint32_t>(raw.size()));
    const esf::PointCloud cloud = pcd_from(file);
    ASSERT_EQ(cloud.points.size(), 2u);
    EXPECT_EQ(bits(cloud.points[0].x()), bits(static_cast<float>(0.1)));
    EXPECT_EQ(cloud.points[0].y(), 2.5f);
    EXPECT_EQ(cloud.points[0].z(), -7.0f);
    EXPECT_EQ(cloud.points[1].x(), -2.0f);
    EXPECT_TRUE(std::isnan(cloud.points[1].y()));
    EXPECT_EQ(cloud.points[1].z(), 1.0f);
    EXPECT_EQ(cloud.labels, (std::vector<std::uint32_t>{3, 4}));

    // The same with the padding block stored (uncompressed size tells which).
    const std::string padded = std::string(6, '\0') + raw;
    const esf::PointCloud again =
        pcd_from(std::string(kMixedHeader) + "DATA binary_compressed\n" +
                 compressed_body(lzf_literals(padded), static_cast<std::uint32_t>(padded.size())));
    expect_same_points(again.points, cloud.points);
    EXPECT_EQ(again.labels, cloud.labels);
}

TEST(PcdRead, LzfBackReferencesIncludingLongOverlappingOnes) {
    // Four points (1, 2, 3): each 16-byte block is a 4-byte literal and a 12-byte back reference
    // at distance 4 (overlapping; long form: ctrl 7 << 5, extra length 12 - 2 - 7 = 3).
    std::string lzf;
    for (const float v : {1.0f, 2.0f, 3.0f}) {
        lzf += '\x03' + Bytes().put(v).str();
        lzf += std::string{'\xe0', '\x03', '\x03'};
    }
    const esf::PointCloud cloud =
        pcd_from(xyz_header(4, "binary_compressed") + compressed_body(lzf, 48));
    ASSERT_EQ(cloud.points.size(), 4u);
    for (const auto& p : cloud.points) EXPECT_EQ(p, Eigen::Vector3f(1, 2, 3));

    // Short form: ctrl (len - 2) << 5, here 3 bytes at distance 1 after "ab": "abbbb".
    std::string raw_lzf = std::string{'\x01', 'a', 'b', '\x20', '\x00'};
    // Pad with literals to 12 bytes = one point of x y z.
    raw_lzf += std::string{'\x06', 'c', 'd', 'e', 'f', 'g', 'h', 'i'};
    const esf::PointCloud one =
        pcd_from(xyz_header(1, "binary_compressed") + compressed_body(raw_lzf, 12));
    const std::string expected_raw = "abbbbcdefghi";
    float x = 0;
    std::memcpy(&x, expected_raw.data(), 4);
    EXPECT_EQ(bits(one.points[0].x()), bits(x));
}

TEST(PcdRead, FloatAndSignedLabels) {
    const esf::PointCloud cloud = pcd_from(
        "FIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nPOINTS 2\nDATA ascii\n"
        "0 0 0 7\n1 1 1 12\n");
    EXPECT_EQ(cloud.labels, (std::vector<std::uint32_t>{7, 12}));
    const std::string negative =
        Bytes()
            .text("FIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F I\nPOINTS 1\nDATA binary\n")
            .put(0.0f)
            .put(0.0f)
            .put(0.0f)
            .put<std::int32_t>(-1)
            .str();
    EXPECT_THAT(io_error([&] { pcd_from(negative); }),
                AllOf(StartsWith("mem.pcd: "), HasSubstr("point 0: label")));
}

// ---------------------------------------------------------------------------------------------
// PCD error paths

TEST(PcdErrors, HeaderProblemsNameLineAndKeyword) {
    auto header_error = [](const std::string& text) { return io_error([&] { pcd_from(text); }); };
    EXPECT_EQ(header_error("VERSION 0.7\nFIELDS x y z\nFOO 1\nDATA ascii\n"),
              "mem.pcd:3: bad header: unknown keyword 'FOO'");
    EXPECT_EQ(header_error("# c\nFIELDS x y z\nSIZE 4 4\nDATA ascii\n"),
              "mem.pcd:3: bad header: SIZE: 2 entries for 3 FIELDS");
    EXPECT_THAT(header_error("FIELDS x y z\nSIZE 4 4 4\nTYPE F Q F\nDATA ascii\n"),
                AllOf(StartsWith("mem.pcd:3: bad header: TYPE: "), HasSubstr("'Q'")));
    EXPECT_THAT(header_error("FIELDS x y z\nSIZE 4 2 4\nTYPE F F F\nPOINTS 0\nDATA ascii\n"),
                AllOf(StartsWith("mem.pcd:3: bad header: TYPE: "),
                      HasSubstr("field 'y' has TYPE F with SIZE 2")));
    EXPECT_THAT(header_error("FIELDS x y z\nSIZE 4 3 4\nDATA ascii\n"),
                StartsWith("mem.pcd:2: bad header: SIZE: size must be 1, 2, 4 or 8"));
    EXPECT_EQ(header_error("SIZE 4 4 4\nFIELDS x y z\nDATA ascii\n"),
              "mem.pcd:1: bad header: SIZE: comes before FIELDS");
    EXPECT_EQ(header_error("FIELDS x y zz\nPOINTS 1\nDATA ascii\n1 2 3\n"),
              "mem.pcd:1: bad header: FIELDS: no field named 'z'");
    EXPECT_EQ(header_error("FIELDS x y z\nCOUNT 1 2 1\nPOINTS 1\nDATA ascii\n1 2 3 4\n"),
              "mem.pcd:1: bad header: COUNT: field 'y' has COUNT 2, expected 1");
    EXPECT_EQ(header_error("FIELDS x y z\nWIDTH 2\nHEIGHT 2\nPOINTS 5\nDATA binary\n"),
              "mem.pcd:4: bad header: POINTS 5 does not equal WIDTH x HEIGHT = 2 x 2");
    EXPECT_EQ(header_error("FIELDS x y z\nWIDTH two\nDATA ascii\n"),
              "mem.pcd:2: bad header: WIDTH: expected an integer in [0, 2^32), got 'two'");
    EXPECT_EQ(header_error("FIELDS x y z\nPOINTS 1e12\nDATA ascii\n"),
              "mem.pcd:2: bad header: POINTS: expected a non-negative integer, got '1e12'");
    EXPECT_EQ(header_error("FIELDS x y z\nPOINTS 1\n"), "mem.pcd:2: bad header: no DATA line");
    EXPECT_EQ(header_error("POINTS 1\nDATA ascii\n1 2 3\n"),
              "mem.pcd:2: bad header: DATA: no FIELDS line before DATA");
    EXPECT_EQ(header_error("FIELDS x y z\nVIEWPOINT 0 0 0\nDATA ascii\n"),
              "mem.pcd:2: bad header: VIEWPOINT: expected 7 values (tx ty tz qw qx qy qz)");
    EXPECT_EQ(header_error("ply\nformat ascii 1.0\n"),
              "mem.pcd:1: bad header: unknown keyword 'ply'");
}

TEST(PcdErrors, UnknownDataType) {
    EXPECT_EQ(io_error([] { pcd_from(xyz_header(1, "zip")); }),
              "mem.pcd:10: unknown DATA type 'zip' (expected ascii, binary or binary_compressed)");
}

TEST(PcdErrors, EmptyInput) {
    EXPECT_EQ(io_error([] { pcd_from(""); }), "mem.pcd: empty file");
}

TEST(PcdErrors, TruncatedBinary) {
    const std::string file = xyz_header(3, "binary") + std::string(30, '\0');
    EXPECT_EQ(io_error([&] { pcd_from(file); }),
              "mem.pcd: truncated: expected 36 bytes of binary data, got 30");
}

// Reading from a path: binary x y z floats go straight into the points after the first 4,096
// bytes are read (a header ending within them); everything else is read whole. Both must give
// what the bytes parse to, whatever the sizes.
void write_file(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
}

std::string binary_xyz(const esf::PointCloud& cloud, const std::string& comment) {
    std::string out = comment + xyz_header(cloud.points.size(), "binary");
    out.append(reinterpret_cast<const char*>(cloud.points.data()), 12 * cloud.points.size());
    return out;
}

TEST(PcdReadFile, BinaryXyzFilesEqualTheirBytesParsed) {
    TempDir dir;
    // Points within the first read, across it and far past it; headers short and longer than
    // the first read (comment lines), and ending exactly at its end.
    const std::string long_comment = "# " + std::string(5000, 'c') + "\n";
    const std::string header = xyz_header(10, "binary");
    const std::string to_the_end = "# " + std::string(4096 - 3 - header.size(), 'e') + "\n";
    ASSERT_EQ((to_the_end + header).size(), 4096u);
    for (const std::size_t n : {1, 10, 340, 341, 1000, 50000})
        for (const std::string& comment : {std::string(), long_comment, to_the_end}) {
            const esf::PointCloud cloud = sample_cloud(n, false);
            const std::string bytes = binary_xyz(cloud, comment);
            const std::string path = dir.file("cloud.pcd");
            write_file(path, bytes);
            const esf::PointCloud read = esf::read_pcd(path);
            const esf::PointCloud parsed = esf::parse_pcd(bytes, path);
            SCOPED_TRACE(std::to_string(n) + " points, comment of " +
                         std::to_string(comment.size()) + " bytes");
            expect_same_points(read.points, parsed.points);
            expect_same_points(read.points, cloud.points);
            EXPECT_EQ(read.width, parsed.width);
            EXPECT_EQ(read.height, parsed.height);
            EXPECT_TRUE(read.labels.empty());
        }
}

TEST(PcdReadFile, ADataLineCutByTheFirstReadIsNotTakenForAnother) {
    // "DATA binary" ends the first 4,096 bytes, but the line goes on: "_compressed".
    TempDir dir;
    const esf::PointCloud cloud = sample_cloud(20, false);
    std::string raw;
    for (int axis = 0; axis < 3; ++axis)
        for (const auto& p : cloud.points) raw += Bytes().put(p[axis]).str();
    const std::string header = xyz_header(20, "binary_compressed");
    const std::size_t cut = header.size() - std::string("_compressed\n").size();
    const std::string comment = "# " + std::string(4096 - cut - 3, 'p') + "\n";
    const std::string bytes =
        comment + header +
        compressed_body(lzf_literals(raw), static_cast<std::uint32_t>(raw.size()));
    ASSERT_EQ(bytes.substr(4096 - 11, 11), "DATA binary");
    const std::string path = dir.file("cut.pcd");
    write_file(path, bytes);
    expect_same_points(esf::read_pcd(path).points, cloud.points);
}

TEST(PcdReadFile, TruncatedAndEmptyFilesGiveTheMessagesOfTheirBytes) {
    TempDir dir;
    const std::string path = dir.file("short.pcd");
    for (const std::size_t n : {3, 2000}) {
        const std::string whole = binary_xyz(sample_cloud(n, false), "");
        const std::string cut = whole.substr(0, whole.size() - 6);
        write_file(path, cut);
        EXPECT_EQ(io_error([&] { esf::read_pcd(path); }),
                  io_error([&] { esf::parse_pcd(cut, path); }));
        EXPECT_THAT(io_error([&] { esf::read_pcd(path); }), HasSubstr("truncated"));
    }
    write_file(path, "");
    EXPECT_EQ(io_error([&] { esf::read_pcd(path); }), path + ": empty file");
    write_file(path, "FIELDS x y z\nPOINTS 2\nDATA bin");
    EXPECT_EQ(io_error([&] { esf::read_pcd(path); }),
              io_error([&] { esf::parse_pcd("FIELDS x y z\nPOINTS 2\nDATA bin", path); }));
}

TEST(PcdErrors, AbsurdPointCountIsCheckedBeforeAllocating) {
    const std::string binary =
        "FIELDS x y z\nWIDTH 1000000\nHEIGHT 1000000\nPOINTS 1000000000000\nDATA binary\n" +
        std::string(12, '\0');
    EXPECT_EQ(io_error([&] { pcd_from(binary); }),
              "mem.pcd: truncated: expected 12000000000000 bytes of binary data, got 12");
    const std::string ascii =
        "FIELDS x y z\nWIDTH 1000000\nHEIGHT 1000000\nPOINTS 1000000000000\nDATA ascii\n1 2 3\n";
    EXPECT_THAT(io_error([&] { pcd_from(ascii); }),
                StartsWith("mem.pcd: truncated: expected 1000000000000 points of ascii data"));
    // Compressed: the stated size must match the header and be reachable from the block.
    const std::string compressed =
        "FIELDS x y z\nWIDTH 1000000\nHEIGHT 1000\nPOINTS 1000000000\nDATA binary_compressed\n" +
        compressed_body(lzf_literals("abcd"), 4);
    EXPECT_THAT(io_error([&] { pcd_from(compressed); }),
                AllOf(StartsWith("mem.pcd: corrupt binary_compressed data: uncompressed size 4 "),
                      HasSubstr("does not match the header")));
    const std::string overflow =
        "FIELDS x y z\nSIZE 4 4 4\nCOUNT 1 1 1\nWIDTH 4294967295\nHEIGHT 4294967295\n"
        "POINTS 18446744065119617025\nDATA binary\n";
    EXPECT_THAT(io_error([&] { pcd_from(overflow); }), StartsWith("mem.pcd: absurd size"));
    const std::string ratio =
        xyz_header(1000, "binary_compressed") + compressed_body(lzf_literals("abcd"), 12000);
    EXPECT_EQ(
        io_error([&] { pcd_from(ratio); }),
        "mem.pcd: corrupt binary_compressed data: 5 compressed bytes cannot hold 12000 bytes");
}

TEST(PcdErrors, TruncatedCompressed) {
    const std::string body =
        pcd_bytes(sample_cloud(100, false), esf::PcdEncoding::kBinaryCompressed);
    EXPECT_THAT(io_error([&] { pcd_from(body.substr(0, body.size() - 10)); }),
                AllOf(StartsWith("mem.pcd: truncated: expected "),
                      HasSubstr(" bytes of binary data, got ")));
    EXPECT_EQ(io_error([&] { pcd_from(xyz_header(1, "binary_compressed") + "abc"); }),
              "mem.pcd: truncated: expected 8 bytes of binary data, got 3");
}

TEST(PcdErrors, CorruptLzf) {
    // A back reference as the very first token points before the output.
    const std::string before_start = std::string{'\x20', '\x00'} + std::string(10, '\x00');
    EXPECT_THAT(
        io_error([&] {
            pcd_from(xyz_header(1, "binary_compressed") + compressed_body(before_start, 12));
        }),
        AllOf(StartsWith("mem.pcd: corrupt LZF data"),
              HasSubstr("back reference before the start of the output")));
    // A literal run longer than the block.
    EXPECT_THAT(io_error([&] {
                    pcd_from(xyz_header(1, "binary_compressed") +
                             compressed_body(std::string{'\x1f', 'a', 'b'}, 12));
                }),
                HasSubstr("corrupt LZF data in binary_compressed block: literal run past the end"));
    // Decodes to fewer bytes than stated.
    EXPECT_EQ(io_error([&] {
                  pcd_from(xyz_header(1, "binary_compressed") +
                           compressed_body(lzf_literals("abcd"), 12));
              }),
              "mem.pcd: corrupt binary_compressed data: decompressed to 4 bytes, expected 12");
}

TEST(PcdErrors, AsciiValues) {
    EXPECT_EQ(io_error([] { pcd_from(xyz_header(2, "ascii") + "1 2 3\n4 abc 6\n"); }),
              "mem.pcd:12: not a number: 'abc' (field 'y')");
    EXPECT_EQ(io_error([] { pcd_from(xyz_header(2, "ascii") + "1 2 3\n\n4 5\n"); }),
              "mem.pcd:13: expected 3 values, got 2");
    EXPECT_EQ(
        io_error([] { pcd_from(xyz_header(3, "ascii") + "1.00 2.00 3.00\n4.00 5.00 6.00\n"); }),
        "mem.pcd:12: truncated: expected 3 points of ascii data, got 2");
    EXPECT_EQ(io_error([] { pcd_from(xyz_header(1, "ascii") + "1 2 3\n4 5 6\n"); }),
              "mem.pcd:12: more data lines than POINTS (1)");
}

TEST(PcdErrors, AsciiValuesBeyondTheFloatRangeNameLineAndValue) {
    EXPECT_EQ(io_error([] { pcd_from(xyz_header(2, "ascii") + "1 2 3\n4 1e39 6\n"); }),
              "mem.pcd:12: out of float range: '1e39' (field 'y')");
    EXPECT_EQ(io_error([] { pcd_from(xyz_header(1, "ascii") + "-1e400 2 3\n"); }),
              "mem.pcd:11: out of float range: '-1e400' (field 'x')");
    // Stored as double in the file, still beyond what the float coordinate can hold.
    EXPECT_EQ(io_error([&] {
                  pcd_from(
                      "FIELDS x y z\nSIZE 8 4 4\nTYPE F F F\nPOINTS 1\n"
                      "DATA ascii\n4e38 0 0\n");
              }),
              "mem.pcd:6: out of float range: '4e38' (field 'x')");
}

TEST(PcdRead, AsciiValuesBelowTheFloatRangeRoundToZeroOrSubnormal) {
    const esf::PointCloud cloud = pcd_from(xyz_header(3, "ascii") +
                                           "1e-50 -1e-50 1e-40\n"
                                           "1e-400 0.000000000000000000000000000000000000000000001 "
                                           "-7e-46\n"
                                           "3.4028235e38 -3.4028235e38 +1.5e-45\n");
    ASSERT_EQ(cloud.points.size(), 3u);
    EXPECT_EQ(bits(cloud.points[0].x()), bits(0.0f));
    EXPECT_EQ(bits(cloud.points[0].y()), bits(-0.0f));
    EXPECT_EQ(cloud.points[0].z(), 1e-40f);  // a subnormal, kept
    EXPECT_TRUE(std::fpclassify(cloud.points[0].z()) == FP_SUBNORMAL);
    EXPECT_EQ(bits(cloud.points[1].x()), bits(0.0f));
    EXPECT_EQ(cloud.points[1].y(), std::numeric_limits<float>::denorm_min());  // 1e-45
    EXPECT_EQ(std::abs(cloud.points[1].z()), 0.0f);
    EXPECT_EQ(cloud.points[2].x(), std::numeric_limits<float>::max());
    EXPECT_EQ(cloud.points[2].y(), std::numeric_limits<float>::lowest());
    EXPECT_EQ(cloud.points[2].z(), std::numeric_limits<float>::denorm_min());
}

// ---------------------------------------------------------------------------------------------
// Robustness: every prefix and random byte flips give a cloud or an IoError, nothing else.

TEST(Robustness, PrefixesAndByteFlips) {
    std::mt19937 gen(11);
    for (const auto encoding : {esf::PcdEncoding::kAscii, esf::PcdEncoding::kBinary,
                                esf::PcdEncoding::kBinaryCompressed}) {
        expect_prefixes_and_flips_read_or_fail(
            pcd_bytes(sample_cloud(20, true), encoding),
            [](const std::string& b) { return pcd_from(b); }, gen);
    }
}

// ---------------------------------------------------------------------------------------------
// Real files against PCL's loader

#ifdef ESF_TEST_WITH_PCL
template <class PointT>
esf::Points pcl_points(const pcl::PointCloud<PointT>& cloud) {
    esf::Points points;
    points.reserve(cloud.size());
    for (const auto& p : cloud) points.emplace_back(p.x, p.y, p.z);
    return points;
}

TEST(RealData, EveryPcdMatchesPclLoader) {
    ESF_REQUIRE_DATA("real");
    std::vector<fs::path> files;
    for (const auto& e : fs::recursive_directory_iterator(esf::test::data_file("real"))) {
        if (e.is_regular_file() && e.path().extension() == ".pcd") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    ASSERT_FALSE(files.empty());
    std::size_t with_labels = 0, organised = 0;
    for (const auto& file : files) {
        SCOPED_TRACE(file.string());
        const esf::PointCloud ours = esf::read_cloud(file.string());
        pcl::PointCloud<pcl::PointXYZ> theirs;
        ASSERT_EQ(pcl::io::loadPCDFile(file.string(), theirs), 0);
        ASSERT_EQ(ours.points.size(), theirs.size());
        EXPECT_EQ(ours.width, theirs.width);
        EXPECT_EQ(ours.height, theirs.height);
        expect_same_points(ours.points, pcl_points(theirs));
        if (ours.organised()) ++organised;
        if (!ours.labels.empty()) {
            ++with_labels;
            pcl::PointCloud<pcl::PointXYZL> labelled;
            ASSERT_EQ(pcl::io::loadPCDFile(file.string(), labelled), 0);
            for (std::size_t i = 0; i < labelled.size(); ++i) {
                ASSERT_EQ(ours.labels[i], labelled[i].label) << "point " << i;
            }
        }
    }
    std::cout << files.size() << " files, " << organised << " organised, " << with_labels
              << " with labels\n";
}
#endif

TEST(RealData, LabelledSceneIsOrganisedWithObjectLabels) {
    ESF_REQUIRE_DATA("real/scenes/mosd_learn0.pcd");
    const esf::PointCloud scene =
        esf::read_pcd(esf::test::data_file("real/scenes/mosd_learn0.pcd").string());
    EXPECT_EQ(scene.width, 640u);
    EXPECT_EQ(scene.height, 480u);
    ASSERT_EQ(scene.points.size(), 640u * 480u);
    ASSERT_EQ(scene.labels.size(), scene.points.size());
    EXPECT_GE(*std::max_element(scene.labels.begin(), scene.labels.end()), 20u);
    const auto finite = esf::drop_non_finite(scene.points);
    EXPECT_GT(finite.dropped, 0u);  // Kinect holes are NaN and are kept by the reader
}

TEST(RealData, MilkReferenceCloud) {
    ESF_REQUIRE_DATA("real/pcl/milk_test.pcd");
    const esf::PointCloud milk = esf::read_cloud(esf::test::data_file("real/pcl/milk_test.pcd"));
    EXPECT_EQ(milk.points.size(), 13704u);
    EXPECT_EQ(milk.width, 13704u);
    EXPECT_EQ(milk.height, 1u);
}

}  // namespace
